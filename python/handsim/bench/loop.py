"""A plain loop of lean steps of one step-benchmark scene, for profilers: ``python -m handsim.bench.loop SCENE N``."""
import sys
import time

from . import step


def main(argv):
    scene = argv[0] if argv else "jewelry_box"
    frames = int(argv[1]) if len(argv) > 1 else 20000
    world, hands, frame, warmup, _ = step.build(scene, "lean", frames_total=300)
    for i in range(-warmup, 0):
        world.step(step.DT, frame(i))
    inputs = [frame(i) for i in range(300)]
    t0 = time.perf_counter()
    for k in range(frames):
        world.step(step.DT, inputs[k % 300])
    print(f"{scene}: {(time.perf_counter() - t0) / frames * 1e6:.1f} us per step (mean, incl. Python)")


if __name__ == "__main__":
    main(sys.argv[1:])
