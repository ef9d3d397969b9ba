/* The jewelry-box scenario every host runs (C, C++ and C# here; the Python tests may compare with the hash the C
 * host writes): the default box, one right hand with lid_pinch_shape(), 60 Hz. For 10 frames the hand closes its
 * pinch on the closed lid's lip; then it swings about the hinge from 0 to 100 degrees (10 past the lid's 90-degree
 * limit) over 120 frames (2 s); then it holds for 20 frames. The schedule uses only +, -, *, / and comparisons, so
 * every language computes bit-identical angles (no libm or JIT transcendental functions involved). The C# test
 * (tests/c_abi/CSharpTest.cs) repeats these numbers; change both together. */
#ifndef HANDSIM_TEST_SCENARIO_H
#define HANDSIM_TEST_SCENARIO_H

#define SCENARIO_FRAMES 150
#define SCENARIO_DT (1.0 / 60.0)

static inline double scenario_angle(int frame) {
  double t = (frame - 10) / 120.0;
  if (t < 0.0) t = 0.0;
  if (t > 1.0) t = 1.0;
  return t * (100.0 * 3.14159265358979323846 / 180.0);
}

#endif
