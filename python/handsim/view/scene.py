"""What a picture of a World shows, as plain numpy arrays: the one scene description that both the live viewer
(:mod:`handsim.view.viewer`, viser in a browser) and the offline renderer (:mod:`handsim.view.raster`, the demo's
and the docs' pictures) draw, so that a picture and the viewer never disagree about what is where.

:class:`Describer` reads a world without changing it (only getters; ``hand_render_vertices`` skins on demand
and leaves the state hash alone, which ``tests/python/test_view.py`` checks) and returns a :class:`Frame`:

* hands as skinned meshes (``hand_render_vertices`` + the model's triangles), skin coloured;
* the hand's particles (deformed, i.e. where they are drawn): the touching ones in red ("contact"), all of them
  with the touching ones red ("all"), or all coloured by hand part: thumb, index, middle, ring, little, palm
  ("part");
* bodies with their shapes (box, sphere, capsule, convex hull, triangle mesh), a body that a hand holds lighter
  and (a box) outlined in gold, labelled with who holds it;
* joints: the axis through the anchor, and a hinge's limits as an arc with a tick at the current angle;
* events of the last second as labels at the body they name.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Dict, List, Optional, Sequence

import numpy as np

from .. import _core

SKIN = (0.93, 0.72, 0.60)
SKIN_BY_SIDE = {"RIGHT": (0.93, 0.72, 0.60), "LEFT": (0.86, 0.66, 0.55)}
GRASPED = (1.0, 0.85, 0.10)  # gold: hue ~50 degrees, clear of the skin's ~20
CONTACT = (0.90, 0.08, 0.08)
FREE_PARTICLE = (0.98, 0.94, 0.90)
PARTS = ("palm", "thumb", "index", "middle", "ring", "little")
PART_COLOURS = {"palm": (0.55, 0.55, 0.60), "thumb": (0.89, 0.10, 0.11), "index": (1.0, 0.50, 0.0),
                "middle": (0.20, 0.63, 0.17), "ring": (0.12, 0.47, 0.71), "little": (0.42, 0.24, 0.60)}
# Named scene objects get colours a newcomer reads at once: a dark teal box with a lighter lid on a grey table.
BODY_COLOURS = {"table": (0.74, 0.74, 0.72), "base": (0.05, 0.42, 0.45), "lid": (0.22, 0.66, 0.66),
                "box": (0.30, 0.45, 0.85)}
OTHER_BODY = (0.45, 0.50, 0.75)
JOINT_COLOUR = (0.10, 0.10, 0.10)
EDGE_COLOUR = (0.08, 0.12, 0.14)
PARTICLE_MODES = ("contact", "all", "part", "none")  # touching only; all, touching red; all by hand part; none
EVENT_SECONDS = 1.0  # how long an event stays on screen: long enough to read at 60 frames per second


@dataclasses.dataclass
class Mesh:
    name: str
    vertices: np.ndarray          # (V, 3) world
    triangles: np.ndarray         # (M, 3) int, counter-clockwise seen from outside
    color: tuple                  # rgb 0..1
    smooth: bool = True           # vertex normals (skin) or one normal per face (boxes)
    kind: str = "body"            # "hand" | "body"
    closed: bool = True           # a closed surface: its back faces are hidden behind its front faces


@dataclasses.dataclass
class Points:
    name: str
    positions: np.ndarray         # (N, 3)
    colors: np.ndarray            # (N, 3) 0..1
    radius: float                 # m


@dataclasses.dataclass
class Lines:
    name: str
    segments: np.ndarray          # (K, 2, 3)
    color: tuple
    width: float = 2.0            # pixels at the viewer's resolution


@dataclasses.dataclass
class Label:
    name: str
    position: np.ndarray          # (3,)
    text: str


@dataclasses.dataclass
class Frame:
    """One moment of a world as primitives, plus what the plots beside the view show."""
    time: float
    meshes: List[Mesh]
    points: List[Points]
    lines: List[Lines]
    labels: List[Label]
    joint_values: Dict[str, float]   # joint name -> value (rad or m)
    grasped: Dict[str, str]          # body name -> "right" / "left" / "right+left"

    def bounds(self, kinds=("hand", "body")) -> np.ndarray:
        """(2, 3) min and max corner of the meshes of the given kinds."""
        pts = [m.vertices for m in self.meshes if m.kind in kinds and len(m.vertices)]
        if not pts:
            return np.zeros((2, 3))
        allp = np.concatenate(pts)
        return np.stack([allp.min(0), allp.max(0)])


def rotate(q, v):
    """Vectors v (..., 3) rotated by the unit quaternion q (x, y, z, w)."""
    q = np.asarray(q, float)
    u, w = q[:3], q[3]
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def transform(pose, local):
    pose = np.asarray(pose, float)
    return pose[:3] + rotate(pose[3:], np.asarray(local, float))


# ---- shapes in their body frame -------------------------------------------------------------------------

def box_mesh(half):
    h = np.asarray(half, float)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float) * h
    # two triangles per face, counter-clockwise seen from outside (corner index = 4 sx + 2 sy + sz)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [[a, b, c] for a, b, c, d in faces] + [[a, c, d] for a, b, c, d in faces]
    return corners, np.array(tris, np.int32)


BOX_EDGES = np.array([(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6),
                      (3, 7)])


def sphere_mesh(radius, rings=12, sectors=24, half_height=0.0):
    """A closed UV sphere (one vertex per pole); with half_height, its halves pulled apart along Y into a
    capsule. Triangles counter-clockwise seen from outside."""
    verts = [[0.0, radius + half_height, 0.0]]
    for i in range(1, rings):
        phi = math.pi * i / rings
        shift = half_height if 2 * i <= rings else -half_height
        for j in range(sectors):
            th = 2 * math.pi * j / sectors
            verts.append([radius * math.sin(phi) * math.cos(th), radius * math.cos(phi) + shift,
                          radius * math.sin(phi) * math.sin(th)])
    verts.append([0.0, -radius - half_height, 0.0])
    bottom = len(verts) - 1

    def ring(i, j):  # vertex j of ring i (1 .. rings-1)
        return 1 + (i - 1) * sectors + j % sectors

    tris = [[0, ring(1, j + 1), ring(1, j)] for j in range(sectors)]
    for i in range(1, rings - 1):
        for j in range(sectors):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            tris += [[a, b, d], [a, d, c]]
    tris += [[bottom, ring(rings - 1, j), ring(rings - 1, j + 1)] for j in range(sectors)]
    return np.array(verts), np.array(tris, np.int32)


def hull_mesh(points):
    """Triangles of the convex hull of `points` (incremental hull, fine for the few dozen points of a shape)."""
    p = np.asarray(points, float)
    n = len(p)
    if n < 4:
        return p, np.zeros((0, 3), np.int32)
    centre = p.mean(0)
    # start from a non-degenerate tetrahedron
    i0 = 0
    i1 = int(np.argmax(np.linalg.norm(p - p[i0], axis=1)))
    d = np.linalg.norm(np.cross(p - p[i0], p[i1] - p[i0]), axis=1)
    i2 = int(np.argmax(d))
    vol = np.abs((p - p[i0]) @ np.cross(p[i1] - p[i0], p[i2] - p[i0]))
    i3 = int(np.argmax(vol))
    if vol[i3] < 1e-15:
        return p, np.zeros((0, 3), np.int32)
    faces = []

    def oriented(a, b, c):
        nrm = np.cross(p[b] - p[a], p[c] - p[a])
        return (a, b, c) if nrm @ (p[a] - centre) > 0 else (a, c, b)

    for f in ((i0, i1, i2), (i0, i1, i3), (i0, i2, i3), (i1, i2, i3)):
        faces.append(oriented(*f))
    for k in range(n):
        if k in (i0, i1, i2, i3):
            continue
        visible = [f for f in faces
                   if np.cross(p[f[1]] - p[f[0]], p[f[2]] - p[f[0]]) @ (p[k] - p[f[0]]) > 1e-12]
        if not visible:
            continue
        edges = {}
        for a, b, c in visible:
            for e in ((a, b), (b, c), (c, a)):
                edges[e] = edges.get(e, 0) + 1
        horizon = [e for e in edges if (e[1], e[0]) not in edges]
        faces = [f for f in faces if f not in visible] + [(a, b, k) for a, b in horizon]
    return p, np.array(faces, np.int32)


def shape_mesh(shape):
    """(vertices, triangles, edges or None) of a Shape in its body frame."""
    t = shape.type
    if t == _core.ShapeType.BOX:
        v, f = box_mesh(shape.half_extents)
        return v, f, BOX_EDGES
    if t == _core.ShapeType.SPHERE:
        v, f = sphere_mesh(shape.radius)
        return v, f, None
    if t == _core.ShapeType.CAPSULE:
        v, f = sphere_mesh(shape.radius, half_height=shape.half_height)
        return v, f, None
    if t == _core.ShapeType.CONVEX_HULL:
        v, f = hull_mesh(shape.points)
        return v, f, None
    v = np.asarray(shape.points, float)
    return v, np.asarray(shape.indices, np.int32).reshape(-1, 3), None


# ---- hands ----------------------------------------------------------------------------------------------

def particle_parts(model) -> np.ndarray:
    """(N,) index into PARTS of each particle: the finger of its most weighted bone, the wrist and the
    metacarpals counted as palm (the thumb's metacarpal too: it is the ball of the thumb, as in the core's
    grasp rule)."""
    bones = np.asarray(model.mesh.bones)[np.asarray(model.particle_vertex)]
    weights = np.asarray(model.mesh.weights)[np.asarray(model.particle_vertex)]
    bone = bones[np.arange(len(bones)), np.argmax(weights, axis=1)]
    names = [_core.JOINT_NAMES[b] for b in bone]
    return np.array([0 if (n in ("palm", "wrist") or n.endswith("metacarpal")) else PARTS.index(n.split("_")[0])
                     for n in names], np.int8)


class Describer:
    """Turns a world into Frames. Holds what does not change between frames (shape tessellations, hand
    triangles and particle parts) and the events of the last EVENT_SECONDS; reads the world with getters
    only. `names` maps body/joint ids to names (a scene's ``objects``); unnamed ones get "body 3" etc."""

    def __init__(self, world, names: Optional[Dict[str, object]] = None, particles: str = "contact"):
        if particles not in PARTICLE_MODES:
            raise ValueError(f"particles: expected one of {PARTICLE_MODES}, got {particles!r}")
        self.world = world
        self.particles = particles
        self.names = {v: k for k, v in (names or {}).items()}
        self._shapes = {}
        self._hands = {}
        self._events: List[tuple] = []  # (time, body name, text)

    def name(self, ident) -> str:
        if ident in self.names:
            return self.names[ident]
        kind = "joint" if isinstance(ident, _core.JointId) else "body"
        return f"{kind} {ident.index}"

    def _hand_side(self, hand) -> str:
        return self._hand(hand)["side"]

    def _hand(self, hand):
        key = (hand.index, hand.generation)
        if key not in self._hands:
            model = self.world.hand_model(hand)
            self._hands[key] = {"triangles": np.asarray(model.triangles, np.int32),
                                "parts": particle_parts(model), "radius": float(model.particle_radius),
                                "side": model.handedness.name.lower()}
        return self._hands[key]

    def _shape(self, body):
        key = (body.index, body.generation)
        if key not in self._shapes:
            self._shapes[key] = shape_mesh(self.world.body_shape(body))
        return self._shapes[key]

    def frame(self) -> Frame:
        w = self.world
        meshes, points, lines, labels = [], [], [], []
        hands = list(w.hands())
        grasped = {}
        contacts = {h: {} for h in range(len(hands))}
        for body in w.bodies():
            name = self.name(body)
            g = w.body_grasp(body)
            holders = [self._hand_side(h) for h in (g.primary, g.secondary) if h is not None] if g.grasped else []
            if holders:
                grasped[name] = "+".join(holders)
            colour = BODY_COLOURS.get(name, OTHER_BODY)
            if name not in BODY_COLOURS and w.body_motion(body) == _core.BodyMotion.STATIC:
                colour = BODY_COLOURS["table"]  # an unnamed static body is furniture: grey, like the table
            if holders:  # lighter, in a thick gold outline: highlighted, and still recognisably itself
                colour = tuple(0.7 * np.asarray(colour) + 0.3)
            local, tris, edges = self._shape(body)
            pose = w.body_pose(body)
            verts = transform(pose, local)
            closed = w.body_shape(body).type != _core.ShapeType.TRIANGLE_MESH
            meshes.append(Mesh(name, verts, tris, colour, smooth=edges is None, kind="body", closed=closed))
            if edges is not None:
                lines.append(Lines(f"{name}/edges", verts[edges], GRASPED if holders else EDGE_COLOUR,
                                   4.0 if holders else 1.5))
            if holders:
                labels.append(Label(f"{name}/grasp", verts.max(0) * [0, 1, 0] + verts.mean(0) * [1, 0, 1]
                                    + [0, 0.02, 0], f"{name}: held by {' + '.join(holders)}"))
            for k, hand in enumerate(hands):
                if w.hand_tracked(hand) and w.body_contact_count(body, hand):
                    contacts[k][name] = np.asarray(w.body_contacts(body, hand)[0])
        for k, hand in enumerate(hands):
            if not w.hand_tracked(hand):
                continue
            info = self._hand(hand)
            side = info["side"]
            meshes.append(Mesh(f"hand_{side}", np.asarray(w.hand_render_vertices(hand)), info["triangles"],
                               SKIN_BY_SIDE[side.upper()], kind="hand"))
            if self.particles != "none":
                pts = np.asarray(w.hand_particles(hand, True))
                touching = np.concatenate(list(contacts[k].values())) if contacts[k] else np.zeros(0, int)
                if self.particles == "contact":  # only the touching ones: the skin stays visible
                    if len(touching):
                        points.append(Points(f"contacts_{side}", pts[touching],
                                             np.tile(CONTACT, (len(touching), 1)), info["radius"]))
                elif self.particles == "all":
                    colours = np.tile(FREE_PARTICLE, (len(pts), 1))
                    colours[touching] = CONTACT
                    points.append(Points(f"particles_{side}", pts, colours, info["radius"]))
                else:
                    colours = np.array([PART_COLOURS[p] for p in PARTS])[info["parts"]]
                    points.append(Points(f"particles_{side}", pts, colours, info["radius"]))
        joint_values = {}
        for joint in w.joints():
            name = self.name(joint)
            s = w.joint_state(joint)
            joint_values[name] = float(s.value)
            lines += self._joint_lines(name, s)
        self._collect_events()
        for t, body, text in self._events:
            if body is not None and w.contains(body):
                pose = np.asarray(w.body_pose(body))
                labels.append(Label(f"event/{t:.3f}/{text}", pose[:3] + [0, 0.08, 0], text))
        return Frame(float(w.time), meshes, points, lines, labels, joint_values, grasped)

    def _collect_events(self):
        now = self.world.time
        self._events = [e for e in self._events if now - e[0] <= EVENT_SECONDS]
        for e in self.world.events():
            what = {_core.EventType.GRASP_BEGIN: "grasp", _core.EventType.GRASP_END: "release",
                    _core.EventType.CONTACT_BEGIN: "touch", _core.EventType.CONTACT_END: "let go"}[e.type]
            side = self._hand_side(e.hand) if self.world.contains(e.hand) else "hand"
            text = f"{side} {what}s {self.name(e.body)}"
            if e.type == _core.EventType.GRASP_END and e.reason != _core.EventReason.NONE:
                text += f" ({e.reason.name.lower().replace('_', ' ')})"
            # contact begin/end flicker every few frames at a lip: only grasps are worth a label
            if e.type in (_core.EventType.GRASP_BEGIN, _core.EventType.GRASP_END):
                self._events.append((now, e.body, text))

    def _joint_lines(self, name, s) -> List[Lines]:
        if s.type == _core.JointType.FIXED:
            return []
        anchor, axis = np.asarray(s.anchor, float), np.asarray(s.axis, float)
        child = np.asarray(self.world.body_pose(s.child), float)[:3]
        reach = max(float(np.linalg.norm(child - anchor)), 0.03)
        out = [Lines(f"{name}/axis", np.array([[anchor - 0.8 * reach * axis, anchor + 0.8 * reach * axis]]),
                     JOINT_COLOUR, 3.0)]
        if s.type != _core.JointType.HINGE:
            return out
        # the child's direction from the axis now, turned back by the current angle, is the direction at 0
        r = child - anchor
        r = r - (r @ axis) * axis
        if np.linalg.norm(r) < 1e-9:
            return out
        r0 = _turn(r / np.linalg.norm(r), axis, -s.value) * 0.6 * reach
        lo = s.lower if math.isfinite(s.lower) else -math.pi
        hi = s.upper if math.isfinite(s.upper) else math.pi
        angles = np.linspace(lo, hi, 33)
        arc = np.array([anchor + _turn(r0, axis, a) for a in angles])
        out.append(Lines(f"{name}/limits", np.stack([arc[:-1], arc[1:]], 1), (0.85, 0.45, 0.05), 2.5))
        ends = [anchor + _turn(r0, axis, a) * 1.15 for a in (lo, hi)]
        out.append(Lines(f"{name}/stops", np.array([[anchor, ends[0]], [anchor, ends[1]]]), (0.85, 0.45, 0.05), 1.5))
        out.append(Lines(f"{name}/value", np.array([[anchor, anchor + _turn(r0, axis, s.value) * 1.3]]),
                         (0.75, 0.05, 0.05), 3.0))
        return out


def _turn(v, axis, angle):
    """v turned by `angle` about the unit `axis` (Rodrigues)."""
    c, s = math.cos(angle), math.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * (axis @ v) * (1 - c)


def describe(world, names: Optional[Dict[str, object]] = None, particles: str = "contact") -> Frame:
    """One Frame of `world` (a fresh Describer: no event history; keep a Describer to have one)."""
    return Describer(world, names, particles).frame()
