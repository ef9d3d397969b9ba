"""Does a picture show what the scene says it should, where the camera should see it?

:func:`expected_masks` rasterizes the Frame's meshes with the viewer's camera into a per-pixel mesh id
(:func:`handsim.view.raster.render` with ``ids=True``) and groups them into classes ("hand", "box");
:func:`classify` sorts a picture's pixels into the same classes by hue (which the shading of a lit surface
hardly changes); :func:`coverage` compares the two.
A screenshot passes when most of each class's expected pixels show that class's colour (*recall*) and most
pixels of that colour lie where the class is expected (*precision*): the hand and the box are drawn, and drawn
in the right place, not just "something is on the page".
"""
from __future__ import annotations

import time
from typing import Dict

import numpy as np

from .scene import BODY_COLOURS, SKIN_BY_SIDE, Frame

CLASSES = {"hand": [SKIN_BY_SIDE["RIGHT"], SKIN_BY_SIDE["LEFT"]],
           "box": [BODY_COLOURS["base"], BODY_COLOURS["lid"]]}
# Hue (degrees) tells the classes apart however a surface is lit: skin ~20, teal ~180 (a held body is drawn
# lighter, which keeps its hue). A renderer's
# lights tint it by some degrees (viser's environment moves the teal ~13 degrees towards blue), far less than
# the gaps; grey (table, background, controls) has no hue to speak of and is left out by its saturation.
HUE_TOLERANCE_DEG = 14.0
MIN_SATURATION = 0.15


def mesh_class(name: str):
    if name.startswith("hand_"):
        return "hand"
    if name in ("base", "lid"):
        return "box"
    return None


def expected_masks(frame: Frame, camera) -> Dict[str, np.ndarray]:
    from .raster import render
    ids = render(frame, camera, ids=True)
    out = {}
    for cls in CLASSES:
        wanted = [i for i, m in enumerate(frame.meshes) if mesh_class(m.name) == cls]
        out[cls] = np.isin(ids, wanted)
    return out


def hue_saturation(rgb):
    """(hue in degrees 0..360, saturation 0..1, value 0..255) of rgb (..., 3) in 0..255 or 0..1 (HSV)."""
    rgb = np.asarray(rgb, float)
    mx, mn = rgb.max(-1), rgb.min(-1)
    span = np.maximum(mx - mn, 1e-9)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    h = np.where(mx == r, (g - b) / span % 6, np.where(mx == g, (b - r) / span + 2, (r - g) / span + 4)) * 60
    return h, (mx - mn) / np.maximum(mx, 1e-9), mx


def _hue_gap(a, b):
    d = np.abs(a - b) % 360
    return np.minimum(d, 360 - d)


def classify(img: np.ndarray) -> Dict[str, np.ndarray]:
    """Per class, the pixels whose hue is within HUE_TOLERANCE_DEG of one of its colours' (saturated enough to
    have a hue, and not nearly black)."""
    h, s, v = hue_saturation(np.asarray(img, float))
    usable = (s >= MIN_SATURATION) & (v > 12)
    out = {}
    for cls, colours in CLASSES.items():
        near = np.zeros(h.shape, bool)
        for col in colours:
            near |= _hue_gap(h, hue_saturation(col)[0]) <= HUE_TOLERANCE_DEG
        out[cls] = usable & near
    return out


def _grow(mask, r):
    """The mask grown by r pixels (a square neighbourhood), without scipy."""
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def coverage(img: np.ndarray, expected: Dict[str, np.ndarray], slack_px: int = 4) -> Dict[str, dict]:
    """Per class: expected pixels, recall (share of the expected pixels, shrunk by `slack_px`, that show the
    class colour) and precision (share of the class-coloured pixels within `slack_px` of where it is
    expected). The slack absorbs edge antialiasing and a pixel or two of projection difference."""
    got = classify(img)
    out = {}
    for cls, want in expected.items():
        inner = want & ~_grow(~want, slack_px)
        near = _grow(want, slack_px)
        n_in, n_got = int(inner.sum()), int(got[cls].sum())
        out[cls] = {"expected_px": int(want.sum()),
                    "recall": float((got[cls] & inner).sum() / n_in) if n_in else 0.0,
                    "precision": float((got[cls] & near).sum() / n_got) if n_got else 0.0}
    return out


def passes(cov: Dict[str, dict], recall: float = 0.6, precision: float = 0.8, min_px: int = 400) -> bool:
    return all(c["expected_px"] >= min_px and c["recall"] >= recall and c["precision"] >= precision
               for c in cov.values())


HIDE_NOTIFICATIONS = ("document.querySelectorAll('.mantine-Notification-closeButton')"
                      ".forEach(b => b.click()); 0")
CANVAS_RECT = ("(() => { let best = null; for (const c of document.querySelectorAll('canvas')) {"
               " const r = c.getBoundingClientRect(); if (!best || r.width * r.height > best[2] * best[3])"
               " best = [r.x, r.y, r.width, r.height]; } return best; })()")


def wait_until_drawn(browser, viewer, timeout: float = 120.0, settle: float = 0.5):
    """Screenshots the page until the 3D view shows the viewer's last frame as expected (or `timeout` runs
    out; then the last screenshot). Returns the screenshot cropped to the 3D view (the controls docked beside
    it are left out); leaves the last measure in `browser.coverage` and the whole page in `browser.page`. A
    software-rendered page (no GPU) may take many seconds per frame on a loaded machine, hence the long but
    bounded wait."""
    deadline = time.monotonic() + timeout
    browser.coverage = None
    if not browser.wait_for(CANVAS_RECT + " !== null", timeout=timeout):
        raise TimeoutError(f"the viewer page showed no 3D view within {timeout:.0f} s")
    img = None
    while time.monotonic() < deadline:
        time.sleep(settle)
        browser.evaluate(HIDE_NOTIFICATIONS)  # "software WebGL" is expected here, and it covers the view
        x, y, w, h = (int(round(v)) for v in browser.evaluate(CANVAS_RECT))
        if w < 16 or h < 16:
            continue
        browser.page = browser.screenshot()
        img = browser.page[y:y + h, x:x + w]
        cam = viewer.camera_for(img.shape[1], img.shape[0])
        browser.coverage = coverage(img, expected_masks(viewer.last_frame, cam))
        if passes(browser.coverage):
            break
    return img
