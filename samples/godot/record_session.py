"""Records the jewelry-box session the Godot sample replays and writes it twice: as a handsim recording
(``session.npz``, :mod:`handsim.recording`) and as the frame stream the Godot host reads (``session.hsframes``,
:mod:`handsim.frame_stream`). The session is the scenario every host runs (``tests/c_abi/scenario.h``): one right
hand arrives open at the closed lid's lip and closes its pinch there over 0.25 s (``closing_grip``) at 60 Hz, from
frame 20 swings it from 0 to 100 degrees over 120 frames, holds for 20. Prints the final state hash, which the C, C# and Godot hosts reach too.

    python samples/godot/record_session.py --out DIR
"""
import argparse
from pathlib import Path

import handsim
from handsim import frame_stream, recording

FRAMES, DT = 160, 1.0 / 60.0  # SCENARIO_FRAMES, SCENARIO_DT of scenario.h
CLOSING_S, SWING_FROM = 0.25, 20  # SCENARIO_CLOSING_S, SCENARIO_SWING_FROM


def scenario_angle(frame: int) -> float:
    """scenario.h's schedule, operation for operation (+, -, *, / only: bit-identical in every language)."""
    t = (frame - SWING_FROM) / 120.0
    t = min(max(t, 0.0), 1.0)
    return t * (100.0 * 3.14159265358979323846 / 180.0)


def record() -> recording.Recording:
    rec = recording.Recorder("jewelry_box", hands=[handsim.HandDef(handedness=handsim.Handedness.RIGHT)],
                             info={"source": "samples/godot/record_session.py (tests/c_abi/scenario.h)"})
    pinch = handsim.lid_pinch_shape()
    for i in range(FRAMES):
        palm = rec.scene.box.lid_pinch_palm(rec.world, handsim.Handedness.RIGHT, scenario_angle(i), 0.0)
        shape = handsim.closing_grip(pinch, i * DT, CLOSING_S)  # scenario_grip_t
        rec.step(DT, {rec.hands[0]: handsim.make_hand_frame(handsim.Handedness.RIGHT, palm, params=shape)})
    return rec.recording


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="folder for session.npz and session.hsframes")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    rec = record()
    rec.save(args.out / "session.npz")
    frame_stream.save(rec, args.out / "session.hsframes")
    print(f"steps {rec.steps} state_hash 0x{int(rec.hashes[-1]):016x}")


if __name__ == "__main__":
    main()
