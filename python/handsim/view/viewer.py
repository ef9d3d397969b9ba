"""The live 3D viewer: a :class:`~handsim.view.scene.Frame` drawn by viser in a web browser.

``Viewer(world).update()`` after each ``world.step`` mirrors the world; ``show(world)`` does the same and returns
the Viewer. The page is served on ``http://HOST:PORT`` (127.0.0.1 unless told otherwise: the viewer sends the
whole scene to whoever connects). Viewing reads the world through getters only: the state hash is the same
with and without a viewer (``tests/python/test_view.py``).
"""
from __future__ import annotations

import dataclasses
import threading
from typing import Dict, Optional

import numpy as np

from . import raster
from .scene import PARTICLE_MODES, Describer, Frame

INSTALL_HINT = "the viewer needs the 'view' extra: pip install 'handsim[view]' (viser)"


def _viser():
    try:
        import viser
    except ImportError as e:
        raise ImportError(INSTALL_HINT) from e
    return viser


def _rgb(c):
    return tuple(int(round(255 * float(v))) for v in c)


def _linear(c):
    """An sRGB colour (what the scene description and the offline pictures use) as the linear value three.js
    expects for a material colour; sent as is, it would show paler than intended."""
    return _rgb(np.clip(np.asarray(c, float), 0, 1) ** 2.2)


def default_camera(frame: Frame, width=1280, height=800) -> raster.Camera:
    """Where a newcomer would stand: in front of the scene (+Z, the user's side), a little to the right and
    above, looking at the hands and the objects they are near (the table alone is not interesting)."""
    parts = [np.asarray(m.vertices) for m in frame.meshes if m.name != "table" and len(m.vertices)]
    if parts:
        v = np.concatenate(parts)
        lo, hi = v.min(0), v.max(0)
    else:
        lo, hi = np.array([-0.3, 0.0, -0.3]), np.array([0.3, 0.6, 0.3])
    return raster.look_at_bounds(lo, hi, direction=(0.55, 0.55, 1.0), fov_deg=40, width=width, height=height)


class Viewer:
    """Mirrors `world` in a browser. `names` maps object names to ids (a scene's ``objects``) for labels and
    colours; `particles` is one of scene.PARTICLE_MODES (also switchable in the page); `shadows` False saves a
    software-rendered page (no GPU) most of its drawing time. `port` 0 picks a free
    port (see :attr:`url`)."""

    def __init__(self, world, names: Optional[Dict[str, object]] = None, host: str = "127.0.0.1", port: int = 8080,
                 particles: str = "contact", camera: Optional[raster.Camera] = None, shadows: bool = True,
                 verbose: bool = False):
        viser = _viser()
        if not isinstance(port, int) or not 0 <= port <= 65535:
            raise ValueError(f"port: expected 0..65535, got {port!r}")
        self.describer = Describer(world, names, particles)
        self.server = viser.ViserServer(host=host, port=port, verbose=verbose)
        self.server.scene.set_up_direction("+y")
        self.server.scene.configure_default_lights(True, cast_shadow=shadows)
        # a dimmer environment than viser's default keeps the skin and the box their colours instead of washing
        # them out to white (what check.py, and a person, tell them apart by)
        self.server.scene.configure_environment_map("studio", environment_intensity=0.35)
        # the controls docked at the right edge, beside the 3D view rather than over it
        self.server.gui.main_panel.dock_right()
        self._lock = threading.Lock()
        self._handles: Dict[str, object] = {}
        self._shapes: Dict[str, tuple] = {}
        self.frames_sent = 0
        self.last_frame: Optional[Frame] = None
        self._camera = camera
        gui = self.server.gui
        self.particle_mode = gui.add_dropdown("particles", PARTICLE_MODES, initial_value=particles)
        self.particle_mode.on_update(lambda _: setattr(self.describer, "particles", self.particle_mode.value))
        self.show_labels = gui.add_checkbox("labels", True)
        self.status = gui.add_markdown("")

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"

    def camera_for(self, width: int, height: int) -> raster.Camera:
        """The camera new pages start from, for a page of `width` x `height` pixels (three.js keeps the
        vertical field of view and widens the horizontal one with the page)."""
        return dataclasses.replace(self._camera, width=int(width), height=int(height))

    def set_camera(self, camera: raster.Camera):
        """Where new browser tabs (and "Reset view") look from, in the raster Camera's terms."""
        ic = self.server.initial_camera
        ic.position = tuple(camera.position)
        ic.look_at = tuple(camera.target)
        ic.up = tuple(camera.up)
        ic.fov = float(np.radians(camera.fov_deg))
        for client in self.server.get_clients().values():
            client.camera.position = tuple(camera.position)
            client.camera.look_at = tuple(camera.target)
            client.camera.up_direction = tuple(camera.up)
            client.camera.fov = float(np.radians(camera.fov_deg))
        self._camera = camera

    def update(self, status: str = "") -> Frame:
        """Reads the world once and sends what changed to every open page. Returns the Frame it drew."""
        frame = self.describer.frame()
        self.draw(frame, status)
        return frame

    def draw(self, frame: Frame, status: str = ""):
        with self._lock, self.server.atomic():
            if self._camera is None:
                self.set_camera(default_camera(frame))
            seen = set()
            for m in frame.meshes:
                seen.add(self._mesh(m))
            for p in frame.points:
                seen.add(self._points(p))
            for ln in frame.lines:
                seen.add(self._lines(ln))
            if self.show_labels.value:
                for lab in frame.labels:
                    seen.add(self._label(lab))
            for name in [n for n in self._handles if n not in seen]:
                self._handles.pop(name).remove()
                self._shapes.pop(name, None)
            grasp = ", ".join(f"{b} held by {h}" for b, h in frame.grasped.items()) or "nothing held"
            joints = ", ".join(f"{j} {np.degrees(v):.1f}°" for j, v in frame.joint_values.items())
            self.status.content = f"**t = {frame.time:.2f} s** · {grasp}" + (f" · {joints}" if joints else "") + \
                                  (f"  \n{status}" if status else "")
        self.server.flush()
        self.frames_sent += 1
        self.last_frame = frame

    # One handle per named primitive: created once, then only its changing properties are sent.
    def _mesh(self, m) -> str:
        key = f"/mesh/{m.name}"
        tris = np.asarray(m.triangles, np.uint32)
        h = self._handles.get(key)
        if h is None or self._shapes.get(key) != (len(m.vertices), len(tris)):
            if h is not None:
                h.remove()
            self._handles[key] = self.server.scene.add_mesh_simple(
                key, np.asarray(m.vertices, np.float32), tris, color=_linear(m.color), flat_shading=not m.smooth,
                side="double", cast_shadow=m.kind == "hand" or m.name != "table")
            self._shapes[key] = (len(m.vertices), len(tris))
        else:
            h.vertices = np.asarray(m.vertices, np.float32)
            if tuple(h.color) != _linear(m.color):
                h.color = _linear(m.color)
        return key

    def _points(self, p) -> str:
        key = f"/points/{p.name}"
        cols = (np.clip(np.asarray(p.colors, float), 0, 1) * 255).astype(np.uint8)
        h = self._handles.get(key)
        if h is None or self._shapes.get(key) != len(p.positions):
            if h is not None:
                h.remove()
            self._handles[key] = self.server.scene.add_point_cloud(
                key, np.asarray(p.positions, np.float32), cols, point_size=p.radius, point_shape="circle",
                precision="float32")
            self._shapes[key] = len(p.positions)
        else:
            h.points = np.asarray(p.positions, np.float32)
            h.colors = cols
        return key

    def _lines(self, ln) -> str:
        key = f"/lines/{ln.name}"
        seg = np.asarray(ln.segments, np.float32).reshape(-1, 2, 3)
        h = self._handles.get(key)
        if h is None or self._shapes.get(key) != len(seg):
            if h is not None:
                h.remove()
            self._handles[key] = self.server.scene.add_line_segments(
                key, seg, _rgb(ln.color), thickness=float(ln.width), thickness_units="screen")
            self._shapes[key] = len(seg)
        else:
            h.points = seg
            h.colors = np.tile(np.array(_rgb(ln.color), np.uint8), (len(seg), 2, 1))
        return key

    def _label(self, lab) -> str:
        key = f"/labels/{lab.name}"
        h = self._handles.get(key)
        if h is None:
            self._handles[key] = self.server.scene.add_label(key, lab.text, position=tuple(lab.position),
                                                             anchor="bottom-center")
        else:
            h.position = tuple(float(v) for v in lab.position)
            if h.text != lab.text:
                h.text = lab.text
        return key

    def close(self):
        self.server.stop()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def show(world, names: Optional[Dict[str, object]] = None, **kwargs) -> Viewer:
    """A Viewer of `world`, already showing its current state; call ``.update()`` after each step."""
    v = Viewer(world, names, **kwargs)
    v.update()
    return v
