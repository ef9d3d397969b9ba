"""Rigged hands from glTF 2.0 files: a :class:`handsim.SkinnedMesh` and its bind :class:`handsim.HandFrame`.

``mesh, bind = load_gltf_hand("Hand_low_L.gltf")`` then ``world.add_hand(HandDef(handedness=bind.handedness),
mesh, bind)``. Reading the file is left to pygltflib (``pip install 'handsim[gltf]'``); it is imported only
when a file is loaded, so ``import handsim`` works without it.

What the loader does, in order:

1. **Geometry.** The first node that has both a mesh and a skin is the hand. Every triangle primitive of its
   mesh is read (POSITION, JOINTS_n/WEIGHTS_n, indices); the vertices are put in the skeleton's rest pose in
   scene space, ``v = sum_k w_k * G_k * IBM_k * v_file`` (G: a joint node's global transform, IBM: its inverse
   bind matrix; the mesh node's own transform is ignored, as the glTF spec says for skinned meshes). glTF is
   right-handed, +Y up, metres, like handsim, so no axis or unit conversion is needed; node scales and an
   armature's rotation are baked in by the formula.
2. **Joint names.** A glTF joint maps to an OpenXR joint (:data:`handsim.JOINT_NAMES`) when its name, split
   into words (``_ . - space`` and camelCase), ends with that joint's words once side markers
   (``l r left right``) and the ``XR_HAND_JOINT_ ... _EXT`` affixes are dropped, with ``pinky`` read as
   ``little``: ``Index_Proximal_L``, ``hand.index.proximal.R``, ``XR_HAND_JOINT_INDEX_PROXIMAL_EXT`` and
   ``LeftIndexProximal`` all name ``index_proximal``. ``joint_map`` overrides or adds mappings.
3. **Weights.** Influences of glTF joints outside the OpenXR set (forearm, twist or helper bones) move to
   their nearest mapped ancestor, or to the wrist. Influences on the same OpenXR joint are merged, the four
   largest kept and renormalized.
4. **Joint positions.** Mapped joints sit at their node's rest position. The wrist, the thumb metacarpal,
   proximal and distal, and the proximal, intermediate and distal joints of the four fingers are required.
   The others are synthesized:

   - ``palm`` is always placed where OpenXR defines it, at the middle of the middle finger's metacarpal
     bone (between the middle metacarpal and proximal joints). A rig's own palm node is ignored: in the
     Godot XR hands it is a grip point 3 cm in front of the palm, and the palm joint is what grasps are held
     relative to.
   - a missing finger metacarpal goes 15 % of the way from the wrist to that finger's proximal joint;
   - a missing tip goes along its distal bone to the end of the skin weighted to that bone, less the bone's
     radius (or, without such skin, 0.8 distal-bone lengths out).
5. **Joint orientations** follow OpenXR (see ``hand.h``): -Z along the bone towards the fingertip, +Y out of
   the back of the hand. The rig's bone axes are not used (rigs differ: Blender bones point along +Y); each
   frame is built from the joint positions. Palm and wrist: -Z from the wrist towards the middle proximal
   joint, X across the knuckles (index to little on a right hand, little to index on a left one), Y = Z x X.
   Finger bones: -Z towards the next joint, X the palm's X made orthogonal (the flexion axis). Thumb bones:
   -Z towards the next joint, +Y the direction halfway between the back of the hand and the thumb's side
   (where the thumb nail faces in a relaxed hand). A tip takes its distal joint's orientation.
6. **Radii**: the median distance of the skin weighted mostly to a joint's bone from that bone's segment (the
   palm: half the thickness of the palm's skin); joints without skin take their neighbour's.
7. **Handedness**: the argument; else side markers in the joint names; else the geometry (the thumb's base
   sits on the palm side of the plane through the wrist and the index and little knuckles).
"""
import re
from pathlib import Path

import numpy as np

from . import _core
from .adapters import skeleton as _skeleton

__all__ = ["load_gltf_hand", "openxr_joint"]

_SIDE_WORDS = {"l": _core.Handedness.LEFT, "left": _core.Handedness.LEFT,
               "r": _core.Handedness.RIGHT, "right": _core.Handedness.RIGHT}
_ALIASES = {"pinky": "little"}
_FINGERS = ("index", "middle", "ring", "little")
_REQUIRED = ["wrist", "thumb_metacarpal", "thumb_proximal", "thumb_distal"] + [
    f"{f}_{b}" for f in _FINGERS for b in ("proximal", "intermediate", "distal")]
_JOINT = {name: i for i, name in enumerate(_core.JOINT_NAMES)}

# glTF accessor component types and element sizes.
_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_ELEMENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_TRIANGLES = 4


def _pygltflib():
    try:
        import pygltflib
    except ImportError as e:
        raise ImportError("handsim.gltf needs pygltflib to read glTF files: pip install 'handsim[gltf]' "
                          "(or pip install pygltflib)") from e
    return pygltflib


def _words(name):
    """Lower-case words of a joint name: camelCase and ``_ . - :`` separators split, side words kept."""
    spaced = re.sub(r"([a-z0-9])([A-Z])", r"\1 \2", name)
    words = [w for w in re.split(r"[^A-Za-z0-9]+", spaced.lower()) if w]
    if words[:3] == ["xr", "hand", "joint"]:
        words = words[3:]
    if words[-1:] == ["ext"]:
        words = words[:-1]
    return [_ALIASES.get(w, w) for w in words]


def openxr_joint(name):
    """``(joint index or None, Handedness or None)`` read from a rig's joint name, as load_gltf_hand does."""
    words = _words(name)
    side = next((_SIDE_WORDS[w] for w in words if w in _SIDE_WORDS), None)
    words = [w for w in words if w not in _SIDE_WORDS]
    for n in (2, 1):
        joint = _JOINT.get("_".join(words[-n:])) if len(words) >= n else None
        if joint is not None:
            return joint, side
    return None, side


class _Reader:
    """Accessors and node transforms of a loaded glTF document."""

    def __init__(self, gltf):
        self.gltf = gltf
        self.buffers = [gltf.get_data_from_buffer_uri(b.uri) for b in gltf.buffers]
        self.parent = {}
        for i, node in enumerate(gltf.nodes):
            for child in node.children or []:
                self.parent[child] = i
        self._global = {}

    def accessor(self, index):
        a = self.gltf.accessors[index]
        if a.sparse is not None:
            raise ValueError(f"accessor {index}: sparse accessors are not supported")
        dtype = np.dtype(_COMPONENT[a.componentType]).newbyteorder("<")
        width = _ELEMENTS[a.type]
        if a.bufferView is None:
            return np.zeros((a.count, width))
        view = self.gltf.bufferViews[a.bufferView]
        data = self.buffers[view.buffer]
        if data is None:
            raise ValueError(f"buffer {view.buffer}: its data could not be read")
        start = (view.byteOffset or 0) + (a.byteOffset or 0)
        stride = view.byteStride or dtype.itemsize * width
        rows = np.ndarray((a.count, width), dtype, buffer=data, offset=start, strides=(stride, dtype.itemsize))
        out = rows.astype(np.float64) if dtype.kind == "f" or a.normalized else rows.astype(np.int64)
        if a.normalized and dtype.kind != "f":
            out /= np.iinfo(dtype).max
        return out

    def local(self, index):
        node = self.gltf.nodes[index]
        if node.matrix is not None:
            return np.array(node.matrix, dtype=np.float64).reshape(4, 4).T  # glTF stores column-major
        m = np.eye(4)
        if node.rotation is not None:
            x, y, z, w = node.rotation
            m[:3, :3] = _quat_matrix(np.array([x, y, z, w], dtype=np.float64))
        if node.scale is not None:
            m[:3, :3] = m[:3, :3] * np.asarray(node.scale, dtype=np.float64)
        if node.translation is not None:
            m[:3, 3] = node.translation
        return m

    def global_transform(self, index):
        if index not in self._global:
            parent = self.parent.get(index)
            local = self.local(index)
            self._global[index] = local if parent is None else self.global_transform(parent) @ local
        return self._global[index]


from .quat import quat_matrix as _quat_matrix  # noqa: E402
_unit = _skeleton.unit
_orientation = _skeleton.orientation


def _skin_node(gltf):
    for i, node in enumerate(gltf.nodes):
        if node.mesh is not None and node.skin is not None:
            return node
    raise ValueError("the file has no skinned mesh (a node with both a mesh and a skin)")


def _read_mesh(reader, node):
    """Positions (file space), per-vertex (joints, weights) of every influence set, triangles."""
    positions, joints, weights, triangles = [], [], [], []
    base = 0
    for p, prim in enumerate(reader.gltf.meshes[node.mesh].primitives):
        if prim.mode not in (None, _TRIANGLES):
            raise ValueError(f"mesh primitive {p}: mode {prim.mode} is not triangles")
        attrs = prim.attributes
        if attrs.POSITION is None or attrs.JOINTS_0 is None or attrs.WEIGHTS_0 is None:
            raise ValueError(f"mesh primitive {p}: needs POSITION, JOINTS_0 and WEIGHTS_0")
        pos = reader.accessor(attrs.POSITION)
        sets = [(reader.accessor(attrs.JOINTS_0), reader.accessor(attrs.WEIGHTS_0))]
        k = 1
        while getattr(attrs, f"JOINTS_{k}", None) is not None and getattr(attrs, f"WEIGHTS_{k}", None) is not None:
            sets.append((reader.accessor(getattr(attrs, f"JOINTS_{k}")), reader.accessor(getattr(attrs, f"WEIGHTS_{k}"))))
            k += 1
        idx = (reader.accessor(prim.indices).reshape(-1) if prim.indices is not None
               else np.arange(len(pos), dtype=np.int64))
        positions.append(pos)
        joints.append(np.hstack([j for j, _ in sets]).astype(np.int64))
        weights.append(np.hstack([w for _, w in sets]))
        triangles.append(idx.reshape(-1, 3) + base)
        base += len(pos)
    widest = max(j.shape[1] for j in joints)
    pad = lambda a: np.pad(a, ((0, 0), (0, widest - a.shape[1])))
    return (np.vstack(positions), np.vstack([pad(j) for j in joints]), np.vstack([pad(w) for w in weights]),
            np.vstack(triangles))


def _map_joints(gltf, skin, joint_map):
    """OpenXR index (or -1) of each skin joint, and the handedness its names suggest (or None)."""
    names = [gltf.nodes[n].name or f"node{n}" for n in skin.joints]
    overrides = {}
    for key, value in (joint_map or {}).items():
        target = _JOINT.get(value) if isinstance(value, str) else value
        if target is None or not 0 <= int(target) < len(_JOINT):
            raise ValueError(f"joint_map[{key!r}]: {value!r} is not an OpenXR joint name or index")
        if key not in names:
            raise ValueError(f"joint_map: the skin has no joint named {key!r}")
        overrides[key] = int(target)
    mapped, sides, owner = [], set(), {}
    for name in names:
        joint, side = openxr_joint(name)
        joint = overrides.get(name, joint)
        if side is not None:
            sides.add(side)
        if joint is not None and joint in owner:
            raise ValueError(f"joints {owner[joint]!r} and {name!r} both map to {_core.JOINT_NAMES[joint]!r}; "
                             "pass joint_map to choose")
        if joint is not None:
            owner[joint] = name
        mapped.append(-1 if joint is None else joint)
    return np.array(mapped), (sides.pop() if len(sides) == 1 else None)


def _route_influences(reader, skin, mapped):
    """OpenXR joint receiving each skin joint's influence: itself, else the nearest mapped ancestor, else
    the wrist."""
    by_node = {node: m for node, m in zip(skin.joints, mapped) if m >= 0}
    route = np.empty(len(skin.joints), dtype=np.int64)
    for i, node in enumerate(skin.joints):
        n = node
        while n is not None and n not in by_node:
            n = reader.parent.get(n)
        route[i] = by_node[n] if n is not None else _core.WRIST
    return route


def _top_four(bones, weights):
    """Merge influences on the same joint, keep the four largest, renormalize."""
    n = len(bones)
    dense = np.zeros((n, _core.JOINT_COUNT))
    np.add.at(dense, (np.repeat(np.arange(n), bones.shape[1]), bones.reshape(-1)), weights.reshape(-1))
    order = np.argsort(-dense, axis=1, kind="stable")[:, :4]
    top = np.take_along_axis(dense, order, axis=1)
    total = top.sum(axis=1, keepdims=True)
    if np.any(total <= 0):
        raise ValueError(f"vertex {int(np.argmax(total[:, 0] <= 0))}: has no skin weight")
    top /= total
    return np.where(top > 0, order, 0), top


def _segment_distance(points, a, b):
    ab = b - a
    t = np.clip((points - a) @ ab / max(ab @ ab, 1e-18), 0, 1)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


_CHILD = {_core.WRIST: _core.PALM}
for _f, _first in [("thumb", _core.THUMB_METACARPAL)] + [(f, _JOINT[f + "_metacarpal"]) for f in _FINGERS]:
    _last = _JOINT[_f + "_tip"]
    _CHILD.update({j: j + 1 for j in range(_first, _last)})


def _synthesize_positions(pos, have, vertices, dominant):
    """Fills palm, finger metacarpals and tips (see the module docstring)."""
    for f in _FINGERS:
        meta, prox = _JOINT[f + "_metacarpal"], _JOINT[f + "_proximal"]
        if not have[meta]:
            pos[meta] = pos[_core.WRIST] + 0.15 * (pos[prox] - pos[_core.WRIST])
    for f in ("thumb",) + _FINGERS:
        tip, distal = _JOINT[f + "_tip"], _JOINT[f + "_distal"]
        if have[tip]:
            continue
        prev = pos[distal - 1]
        length = np.linalg.norm(pos[distal] - prev)
        direction = _unit(pos[distal] - prev, f"the {f} distal bone")
        skin = vertices[dominant == distal]
        reach = 0.8 * length
        if len(skin):
            along = (skin - pos[distal]) @ direction
            radius = np.median(np.linalg.norm(skin - pos[distal] - along[:, None] * direction, axis=1))
            reach = max(along.max() - radius, 0.5 * length)
        pos[tip] = pos[distal] + reach * direction
    pos[_core.PALM] = 0.5 * (pos[_core.MIDDLE_METACARPAL] + pos[_core.MIDDLE_PROXIMAL])


def _orientations(pos, handedness):
    return _skeleton.orientations(pos, handedness)


def _radii(pos, quats, vertices, dominant):
    radii = np.full(_core.JOINT_COUNT, np.nan)
    for j, child in _CHILD.items():
        skin = vertices[dominant == j]
        if len(skin):
            radii[j] = np.median(_segment_distance(skin, pos[j], pos[child]))
    metacarpals = [_JOINT[f + "_metacarpal"] for f in _FINGERS]
    palm_skin = vertices[np.isin(dominant, metacarpals + [_core.PALM])]
    if len(palm_skin):
        back = _quat_matrix(quats[_core.PALM])[:, 1]
        radii[_core.PALM] = np.median(np.abs((palm_skin - pos[_core.PALM]) @ back))
    # Joints without skin of their own (tips, unweighted palm or metacarpals) take a neighbour's radius.
    for j in list(range(_core.JOINT_COUNT)) + list(range(_core.JOINT_COUNT - 1, -1, -1)):
        if np.isnan(radii[j]):
            near = [k for k in (j - 1, j + 1) if 0 <= k < _core.JOINT_COUNT and not np.isnan(radii[k])]
            if near:
                radii[j] = radii[near[0]]
    return np.nan_to_num(radii, nan=0.01)


def _geometric_handedness(pos):
    """RIGHT if the thumb's base lies on the palm side of a right hand's palm frame, else LEFT."""
    normal = np.cross(pos[_core.INDEX_PROXIMAL] - pos[_core.WRIST], pos[_core.LITTLE_PROXIMAL] - pos[_core.WRIST])
    # For a right hand (fingers -Z, little finger +X) this normal points out of the palm (-Y); for a left
    # hand, the mirror image, out of the back of the hand.
    thumb = 0.5 * (pos[_core.THUMB_METACARPAL] + pos[_core.THUMB_PROXIMAL]) - pos[_core.WRIST]
    return _core.Handedness.RIGHT if thumb @ normal > 0 else _core.Handedness.LEFT


def load_gltf_hand(path, handedness=None, joint_map=None):
    """Loads a skinned hand from a glTF 2.0 file (.gltf or .glb).

    Returns ``(SkinnedMesh, HandFrame)``: the mesh in the skeleton's rest pose (scene space, metres) and the
    bind frame on the 26 OpenXR joints, ready for ``World.add_hand(HandDef(handedness=bind.handedness), mesh,
    bind)``. ``handedness`` (a :class:`handsim.Handedness`) overrides what the joint names or the geometry
    say; ``joint_map`` maps rig joint names to OpenXR joint names or indices. The module docstring says how
    joints are matched and how missing ones are synthesized. Raises ImportError without pygltflib,
    FileNotFoundError, and ValueError naming what the file lacks.
    """
    if handedness is not None and not isinstance(handedness, _core.Handedness):
        raise TypeError(f"handedness: expected a Handedness or None, got {type(handedness).__name__}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"path: no such file: {path}")
    pygltflib = _pygltflib()
    gltf = pygltflib.GLTF2().load(str(path))
    if gltf is None:
        raise ValueError(f"path: {path} could not be read as glTF")
    try:
        return _build(gltf, handedness, joint_map)
    except ValueError as e:
        raise ValueError(f"{path.name}: {e}") from None


def _build(gltf, handedness, joint_map):
    reader = _Reader(gltf)
    node = _skin_node(gltf)
    skin = gltf.skins[node.skin]
    mapped, named_side = _map_joints(gltf, skin, joint_map)
    missing = [name for name in _REQUIRED if _JOINT[name] not in mapped]
    if missing:
        raise ValueError("the skin lacks the OpenXR joints " + ", ".join(missing) +
                         " (names are matched as the handsim.gltf docstring says; pass joint_map)")

    # Rest pose in scene space: v = sum_k w_k G_k IBM_k v_file.
    count = len(skin.joints)
    ibm = (reader.accessor(skin.inverseBindMatrices).reshape(count, 4, 4).transpose(0, 2, 1)
           if skin.inverseBindMatrices is not None else np.tile(np.eye(4), (count, 1, 1)))
    globals_ = np.array([reader.global_transform(n) for n in skin.joints])
    skinning = globals_ @ ibm
    file_positions, joints, weights, triangles = _read_mesh(reader, node)
    if joints.max(initial=0) >= count or joints.min(initial=0) < 0:
        raise ValueError("JOINTS_0 names a joint outside the skin")
    homogeneous = np.hstack([file_positions, np.ones((len(file_positions), 1))])
    blended = np.einsum("vk,vkij->vij", weights, skinning[joints])
    vertices = np.einsum("vij,vj->vi", blended, homogeneous)[:, :3]

    bones, bone_weights = _top_four(_route_influences(reader, skin, mapped)[joints], weights)
    dominant = bones[:, 0]

    pos = np.zeros((_core.JOINT_COUNT, 3))
    have = np.zeros(_core.JOINT_COUNT, dtype=bool)
    for k, j in enumerate(mapped):
        if j >= 0:
            pos[j] = globals_[k][:3, 3]
            have[j] = True
    have[_core.PALM] = False  # always synthesized (module docstring, step 4)
    _synthesize_positions(pos, have, vertices, dominant)
    side = handedness if handedness is not None else named_side
    if side is None:
        side = _geometric_handedness(pos)
    quats = _orientations(pos, side)
    radii = _radii(pos, quats, vertices, dominant)
    mesh = _core.SkinnedMesh(vertices, bones, bone_weights, triangles)
    bind = _core.HandFrame(side, pos, quats, radii, np.ones(_core.JOINT_COUNT, dtype=bool))
    return mesh, bind
