/* The jewelry-box scenario every host runs (C, C++ and C# here; the Python tests may compare with the hash the C
 * host writes): the default box, one right hand, 60 Hz. The hand arrives open at the closed lid's lip and closes
 * its pinch (lid_pinch_shape) over SCENARIO_CLOSING_S, as people do (handsim_closing_grip at t = frame *
 * SCENARIO_DT; the default grasp rule begins a grasp only while the hand closes); from frame SCENARIO_SWING_FROM it
 * swings about the hinge from 0 to 100 degrees (10 past the lid's 90-degree limit) over 120 frames (2 s); then it
 * holds for 20 frames. The schedule uses only +, -, *, / and comparisons, so every language computes bit-identical
 * angles and times (no libm or JIT transcendental functions involved). The C# test (tests/c_abi/CSharpTest.cs) and
 * tests/python/test_determinism.py repeat these numbers; change them together. */
#ifndef HANDSIM_TEST_SCENARIO_H
#define HANDSIM_TEST_SCENARIO_H

#define SCENARIO_FRAMES 160
#define SCENARIO_DT (1.0 / 60.0)
#define SCENARIO_CLOSING_S 0.25 /* core hand.h kGripClosingS: a reach closes its grip over its last quarter second */
#define SCENARIO_SWING_FROM 20  /* the 15 closing frames, grasp_time_s (2 frames) and a few frames' margin */

static inline double scenario_angle(int frame) {
  double t = (frame - SCENARIO_SWING_FROM) / 120.0;
  if (t < 0.0) t = 0.0;
  if (t > 1.0) t = 1.0;
  return t * (100.0 * 3.14159265358979323846 / 180.0);
}

/* The time since the hand began to close its pinch (handsim_closing_grip's t). */
static inline double scenario_grip_t(int frame) { return frame * SCENARIO_DT; }

#endif
