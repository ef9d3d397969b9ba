"""Step time of a world of free boxes (no hands): the cost of the Bullet backend alone."""
import handsim

from . import format_table, summary, time_calls


def build(n_boxes):
    world = handsim.World()
    for i in range(n_boxes):
        world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05] * 3), mass=0.5,
                                       pose=[0.3 * (i % 5), 0.06 + 0.11 * (i // 5), 0, 0, 0, 0, 1]))
    for _ in range(120):  # let the stack settle so the timed frames are steady-state
        world.step(1 / 60)
    return world


def run(quick=False):
    repeats = 200 if quick else 2000
    steps = []
    for n in (1, 10, 50):
        world = build(n)
        steps.append({"bodies": n, **summary(time_calls(lambda: world.step(1 / 60), repeats))})
    return {"steps": steps}


def table(result):
    rows = [(s["bodies"], f"{s['median_s'] * 1e6:.1f}", f"{s['p99_s'] * 1e6:.1f}") for s in result["steps"]]
    return "world step (60 Hz frame, 4 substeps)\n" + format_table(["bodies", "median us", "p99 us"], rows)
