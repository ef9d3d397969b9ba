"""The main demo: a small stack of boxes falls and comes to rest; prints what happened."""
import handsim


def main():
    world = handsim.World()
    boxes = [world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05] * 3), mass=0.3,
                                            pose=[0.0, 0.3 + 0.15 * i, 0.0, 0, 0, 0, 1]))
             for i in range(3)]
    for frame in range(180):
        world.step(1 / 60)
    print(f"handsim {handsim.__version__}: 3 boxes dropped, after {world.time:.1f} s:")
    for i, box in enumerate(boxes):
        x, y, z = world.body_pose(box)[:3]
        print(f"  box {i}: at ({x:+.3f}, {y:.3f}, {z:+.3f}) m")
    print(f"state hash {world.state_hash():#018x}")


if __name__ == "__main__":
    main()
