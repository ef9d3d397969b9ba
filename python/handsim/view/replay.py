"""A recording in the viewer: a timeline slider, play/pause, speed, and the lid angle / grasp state plotted
beside the 3D view.

A recording replays bit for bit (``handsim.recording``), so the app keeps one live world and never stores
meshes: stepping forward steps the world; going back rebuilds it and replays up to the chosen step (a step
costs tens of microseconds, so even thousands of steps take a fraction of a second). The plots come from one
pass over the whole recording when it is opened.
"""
from __future__ import annotations

import math
import threading
import time
from typing import Optional

import numpy as np

from .. import _core
from .. import recording as _rec
from .viewer import Viewer

SPEEDS = ("0.1", "0.25", "0.5", "1", "2", "4")


def trace(rec: _rec.Recording) -> dict:
    """Per step: time, the hinge angle in degrees (NaN without a hinge) and 1 where a hand holds a body."""
    t, lid, held = [], [], []

    def on_step(i, world, scene):
        t.append(world.time)
        lid.append(math.degrees(world.joint_state(scene["hinge"]).value) if "hinge" in scene.objects else np.nan)
        held.append(float(any(world.body_grasp(b).grasped for k, b in scene.objects.items()
                              if isinstance(b, _core.BodyId) and k != "table")))

    result = _rec.replay(rec, on_step)
    return {"t": np.asarray(t), "lid": np.asarray(lid), "held": np.asarray(held), "matches": result.matches}


class ReplayApp:
    """The viewer on a Recording. `step` is the step shown first; `playing` whether it plays at once."""

    def __init__(self, rec: _rec.Recording, title: str = "", step: int = 0, playing: bool = True, **viewer_args):
        _rec.check(rec)
        if rec.steps == 0:
            raise ValueError("recording: it has no steps to show")
        if not isinstance(step, int) or not 0 <= step < rec.steps:
            raise ValueError(f"step: expected 0..{rec.steps - 1}, got {step!r}")
        self.rec = rec
        self.trace = trace(rec)
        self._edits = sorted(rec.edits, key=lambda e: e["step"])
        self._lock = threading.RLock()
        self._build()
        self.viewer = Viewer(self.world, self.scene.objects, **viewer_args)
        gui = self.viewer.server.gui
        gui.add_markdown(f"**{title or 'recording'}**: {rec.scene}, {rec.steps} steps, "
                         f"{float(np.sum(rec.dt)):.2f} s")
        self.slider = gui.add_slider("step", min=0, max=rec.steps - 1, step=1, initial_value=0)
        self.play = gui.add_checkbox("play", playing)
        self.speed = gui.add_dropdown("speed", SPEEDS, initial_value="1")
        self._plot = self._add_plot(gui)
        self.slider.on_update(lambda _: self.seek(int(self.slider.value)))
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self.seek(step)

    def _build(self):
        self.world, self.scene, self.hands = _rec.build_world(self.rec)
        self.index = -1  # the last step applied; -1: none yet
        self._k = 0

    def _advance(self):
        i = self.index + 1
        while self._k < len(self._edits) and self._edits[self._k]["step"] == i:
            _rec.apply_edit(self.world, self.scene, self._edits[self._k])
            self._k += 1
        self.world.step(float(self.rec.dt[i]), self.rec.inputs(i, self.hands))
        self.index = i

    def seek(self, step: int):
        """Shows the world after `step` (clamped to the recording)."""
        step = int(min(max(step, 0), self.rec.steps - 1))
        with self._lock:
            if step == self.index:
                return
            if step < self.index:
                # the Describer names objects by id; rebuilt objects get fresh ids, so the viewer is re-pointed
                self._build()
                self.viewer.describer.__init__(self.world, self.scene.objects, self.viewer.describer.particles)
            while self.index < step:
                self._advance()
            self.viewer.update(self._status())
            if int(self.slider.value) != step:
                self.slider.value = step
            self._mark(step)

    def _status(self):
        i = self.index
        held = "held" if self.trace["held"][i] else "free"
        lid = self.trace["lid"][i]
        return f"step {i} / {self.rec.steps - 1}" + ("" if np.isnan(lid) else f" · lid {lid:.1f}°") + f" · {held}"

    def _add_plot(self, gui):
        t = self.trace["t"]
        top = 90.0 if np.all(np.isnan(self.trace["lid"])) else max(90.0, float(np.nanmax(self.trace["lid"])))
        series = ({"label": "t (s)"}, {"label": "lid angle (deg)", "stroke": "#b8860b", "width": 2},
                  {"label": "grasped (90 = held)", "stroke": "#1f77b4", "width": 1.5})
        # the x range is the whole recording, so the curves grow up to the step shown (where they end is "now")
        scales = {"x": {"time": False, "auto": False, "range": [float(t[0]), float(t[-1])]},
                  "y": {"auto": False, "range": [-2.0, top + 2.0]}}
        return gui.add_uplot(self._plot_data(0), series, scales=scales, title="lid angle and grasp", aspect=1.6)

    def _plot_data(self, step):
        n = step + 1
        return (self.trace["t"][:n], np.nan_to_num(self.trace["lid"][:n], nan=0.0), 90.0 * self.trace["held"][:n])

    def _mark(self, step):
        self._plot.data = self._plot_data(step)

    def run(self, seconds: Optional[float] = None):
        """Plays (while 'play' is ticked) in real time times the chosen speed; returns after `seconds` or on
        close()."""
        end = None if seconds is None else time.monotonic() + seconds
        last = time.monotonic()
        while not self._stop.is_set() and (end is None or time.monotonic() < end):
            now = time.monotonic()
            if self.play.value:
                speed = float(self.speed.value)
                t_target = self.world.time + (now - last) * speed
                step = self.index
                t = self.trace["t"]
                while step + 1 < self.rec.steps and t[step + 1] <= t_target:
                    step += 1
                if step == self.rec.steps - 1 and self.index == step:
                    self.play.value = False  # the end: stop, the user can scrub back
                elif step != self.index:
                    self.seek(step)
            last = now
            time.sleep(1 / 60)

    def close(self):
        self._stop.set()
        self.viewer.close()
