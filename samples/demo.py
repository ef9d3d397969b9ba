"""The main demo (``make demo``): the paper's jewelry box, opened and closed by a two-handed simulated user.

The left hand holds the base; the right hand pinches the lid's lip with the thumb under it, swings it open and
lets go, then tips the open lid over from behind with a flat hand, and it falls shut (handsim.demo). Writes under
out/demo/ (or the folder given as the first argument) shaded 3D pictures rendered from the viewer's scene
description: filmstrip.png (eight moments), demo.gif (the whole session), closeup_lip.png (the thumb under the
lid's lip), plus lid_angle.png and summary.txt. To watch it live in a browser: python -m handsim.view --demo
"""
import sys

from handsim.view import pictures


def main(out_dir="out/demo"):
    return pictures.demo(out_dir)


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
