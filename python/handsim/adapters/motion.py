"""Tracker-neutral recorded motion: what every adapter that reads a whole recording (Leap, BVH) returns and what
:mod:`handsim.replay` plays back. Here rather than in replay so that adapters need not import the replay."""
from __future__ import annotations

import dataclasses
from typing import Dict, List, Optional

import numpy as np

from . import skeleton as _sk

HANDS = ("right", "left")


@dataclasses.dataclass
class Motion:
    """Tracker-neutral input: times (N,) s and per frame {"right"/"left": AdaptedFrame}; closure (N, 2) of
    [right, left] with grab/pinch strengths when the tracker gives them (NaN otherwise)."""
    name: str
    times: np.ndarray
    frames: List[Dict[str, _sk.AdaptedFrame]]
    grab: Optional[np.ndarray] = None
    pinch: Optional[np.ndarray] = None
    source: str = ""
    # what the adapter had to make up, {case: count} (adapters.leap.LeapRecording.notes)
    notes: Dict[str, int] = dataclasses.field(default_factory=dict)

    def palms(self, side=None):
        """(K, 3) palm positions of every tracked frame of `side` ("right", "left"; None: both)."""
        return np.array([f[s].frame.palm_pose[:3] for f in self.frames for s in HANDS
                         if s in f and (side is None or s == side) and f[s].frame.tracked])



def with_strengths(motion: Motion) -> Motion:
    """`motion` with grab and pinch strengths from the skeleton (:func:`skeleton.closure_strengths`) for each
    hand the tracker gave none for (BVH, Leap before 2.0), so that the closing hand and the expectations of a
    replay do not depend on which tracker recorded it; its source then says so."""
    n = len(motion.frames)
    grab = np.full((n, 2), np.nan) if motion.grab is None else np.array(motion.grab, float)
    pinch = np.full((n, 2), np.nan) if motion.pinch is None else np.array(motion.pinch, float)
    derived = []
    for col, side in enumerate(HANDS):
        if not (np.all(np.isnan(grab[:, col])) and np.all(np.isnan(pinch[:, col]))):
            continue
        seen = [i for i, f in enumerate(motion.frames) if side in f and f[side].frame.tracked]
        for i in seen:
            grab[i, col], pinch[i, col] = _sk.closure_strengths(motion.frames[i][side].frame)
        if seen:
            derived.append(side)
    if not derived:
        return motion
    return dataclasses.replace(motion, grab=grab, pinch=pinch,
                               source=f"{motion.source} (grab and pinch of the {' and '.join(derived)} hand "
                                      f"from the skeleton)")
