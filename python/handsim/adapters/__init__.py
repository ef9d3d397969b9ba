"""Adapters from hand trackers to handsim's OpenXR :class:`handsim.HandFrame` (numpy in, frames out).

* :mod:`.openxr`: OpenXR joints as they are (the canonical form) and Unity's left-handed convention;
* :mod:`.mrtk`: MRTK articulated hand poses (Unity JSON);
* :mod:`.mediapipe`: MediaPipe Hands' 21 landmarks (image or world coordinates);
* :mod:`.leap`: Leap Motion recordings of leapjs-playback (``.json.lz``);
* :mod:`.bvh`: BVH motion capture (Perception Neuron style);
* :mod:`.skeleton`: the shared rules for orienting joints from positions and filling missing joints.

Every adapter returns :class:`AdaptedFrame` objects: ``.frame`` (the HandFrame), ``.synthesized`` (joints the
source lacked, made up by the rules of :mod:`.skeleton`) and ``.invalid`` (joints flagged invalid).
See ``docs/input.md``.
"""
from .skeleton import AdaptedFrame, joint_angles, untracked  # noqa: F401
from .leap import LeapRecording, load_leap_recording, read_leap_json  # noqa: F401
from .openxr import from_openxr, from_unity, unity_to_openxr  # noqa: F401,E402
from .mrtk import load_mrtk_pose, read_mrtk_pose  # noqa: F401,E402
from .mediapipe import from_mediapipe  # noqa: F401,E402
from .bvh import hand_frames as bvh_hand_frames, load_bvh, parse_bvh, write_bvh  # noqa: F401,E402
