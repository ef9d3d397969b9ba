"""Offline pictures of a :class:`~handsim.view.scene.Frame`: a small z-buffered software rasterizer in numpy
(perspective camera, Gouraud-shaded skin, flat-shaded boxes, particles as discs, lines, a shadow cast
straight down by a light overhead, labels). It needs neither a GPU nor a browser, so ``make demo`` and the
docs' pictures run anywhere; it draws the same Frame the live viewer does, through the same :class:`Camera`.

Everything is turned into fragments (pixel, depth, colour); the nearest fragment of each pixel wins. Pictures
are rendered at ``supersample`` times the size and averaged down, which smooths the edges.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional, Sequence

import numpy as np

from .scene import Frame

BACKGROUND_TOP = np.array([0.97, 0.97, 0.98])
BACKGROUND_BOTTOM = np.array([0.80, 0.83, 0.87])


@dataclasses.dataclass
class Camera:
    """A perspective camera: eye `position`, looking at `target`, `up` hint, vertical field of view in degrees
    (three.js convention, which viser uses), image `width` x `height` pixels."""
    position: Sequence[float]
    target: Sequence[float]
    up: Sequence[float] = (0.0, 1.0, 0.0)
    fov_deg: float = 40.0
    width: int = 800
    height: int = 600
    near: float = 0.01

    def __post_init__(self):
        for arg in ("position", "target", "up"):
            v = np.asarray(getattr(self, arg), float)
            if v.shape != (3,) or not np.isfinite(v).all():
                raise ValueError(f"camera.{arg}: expected 3 finite numbers, got {getattr(self, arg)!r}")
            setattr(self, arg, v)
        if not np.linalg.norm(self.target - self.position) > 1e-9:
            raise ValueError("camera.target: must differ from camera.position")
        if not 1.0 <= float(self.fov_deg) <= 170.0:
            raise ValueError(f"camera.fov_deg: expected 1..170 degrees, got {self.fov_deg!r}")
        if int(self.width) < 8 or int(self.height) < 8:
            raise ValueError(f"camera.width/height: expected at least 8 pixels, got {self.width}x{self.height}")

    def basis(self):
        """(right, up, forward) unit vectors, world frame."""
        f = self.target - self.position
        f = f / np.linalg.norm(f)
        r = np.cross(f, self.up)
        if np.linalg.norm(r) < 1e-9:  # looking along `up`: any right-angle right vector will do
            r = np.cross(f, [1.0, 0, 0]) if abs(f[0]) < 0.9 else np.cross(f, [0, 0, 1.0])
        r = r / np.linalg.norm(r)
        return r, np.cross(r, f), f

    @property
    def focal(self) -> float:
        """Focal length in pixels (vertical field of view)."""
        return 0.5 * self.height / math.tan(math.radians(self.fov_deg) / 2)

    def project(self, points) -> np.ndarray:
        """(N, 3): pixel x (right), pixel y (down), depth along the view direction (m)."""
        p = np.asarray(points, float).reshape(-1, 3) - self.position
        r, u, f = self.basis()
        z = p @ f
        zs = np.where(z > self.near, z, np.nan)
        x = 0.5 * self.width + self.focal * (p @ r) / zs
        y = 0.5 * self.height - self.focal * (p @ u) / zs
        return np.stack([x, y, z], 1)

    def scaled(self, k: int) -> "Camera":
        return dataclasses.replace(self, width=int(self.width * k), height=int(self.height * k))


def look_at_bounds(lo, hi, direction=(0.6, 0.45, 1.0), fov_deg=35.0, width=800, height=600, margin=1.15) -> Camera:
    """A camera looking from `direction` at the box lo..hi, far enough that it fills the picture."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    centre = 0.5 * (lo + hi)
    radius = 0.5 * np.linalg.norm(hi - lo) * margin
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    half = math.radians(fov_deg) / 2
    half = min(half, math.atan(math.tan(half) * width / height))
    return Camera(centre + d * radius / math.sin(half), centre, fov_deg=fov_deg, width=width, height=height)


# ---- shading --------------------------------------------------------------------------------------------

LIGHT = np.array([-0.35, 0.85, 0.40])
LIGHT = LIGHT / np.linalg.norm(LIGHT)


def _vertex_normals(v, t):
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    out = np.zeros_like(v)
    for k in range(3):
        np.add.at(out, t[:, k], n)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)


def _shade(normals, colour, view_dir):
    """Lambert from the key light and a head light, plus ambient; normals facing away are flipped (two-sided),
    with a small rim term so silhouettes read against the background."""
    n = normals * np.where((normals @ -view_dir) < 0, -1.0, 1.0)[:, None]
    key = np.clip(n @ LIGHT, 0, 1)
    head = np.clip(n @ -view_dir, 0, 1)
    spec = np.clip(n @ ((LIGHT - view_dir) / np.linalg.norm(LIGHT - view_dir)), 0, 1) ** 24
    c = np.asarray(colour, float) * (0.32 + 0.48 * key + 0.28 * head)[:, None] + 0.12 * spec[:, None]
    return np.clip(c, 0, 1)


# ---- fragments --------------------------------------------------------------------------------------------

def _triangle_fragments(cam, xyz, cols_per_vertex, cull: bool):
    """Fragments of the triangles xyz (M, 3, 3 projected) with per-vertex colours (M, 3, 3). With `cull`, the
    triangles facing away are dropped (closed meshes: the ones facing the camera cover them)."""
    ok = np.isfinite(xyz).all(axis=(1, 2))
    xyz, cols = xyz[ok], cols_per_vertex[ok]
    area = (xyz[:, 1, 0] - xyz[:, 0, 0]) * (xyz[:, 2, 1] - xyz[:, 0, 1]) - \
           (xyz[:, 2, 0] - xyz[:, 0, 0]) * (xyz[:, 1, 1] - xyz[:, 0, 1])
    # counter-clockwise seen from outside turns clockwise (negative area) on a y-down screen
    keep = (area < -1e-12) if cull else (np.abs(area) > 1e-12)
    lo = np.maximum(np.floor(xyz[:, :, :2].min(1)).astype(np.int64), 0)
    hi = np.minimum(np.ceil(xyz[:, :, :2].max(1)).astype(np.int64), [cam.width - 1, cam.height - 1])
    keep &= (hi[:, 0] >= lo[:, 0]) & (hi[:, 1] >= lo[:, 1])
    xyz, cols, lo, hi, area = xyz[keep], cols[keep], lo[keep], hi[keep], area[keep]
    w = hi[:, 0] - lo[:, 0] + 1
    h = hi[:, 1] - lo[:, 1] + 1
    count = w * h
    out = ([], [], [])
    big = count > 1024
    small = np.flatnonzero(~big)
    if len(small):
        # the many small ones (the hand's) all at once: one row per (triangle, pixel of its bounding box)
        n = count[small]
        tri = np.repeat(small, n)
        k = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
        px = lo[tri, 0] + k % w[tri]
        py = lo[tri, 1] + k // w[tri]
        _emit(out, cam, xyz, cols, area, tri, px, py)
    for i in np.flatnonzero(big):  # big ones (bodies, the table) one at a time, over their bounding box
        py, px = np.mgrid[lo[i, 1]:hi[i, 1] + 1, lo[i, 0]:hi[i, 0] + 1]
        _emit(out, cam, xyz, cols, area, np.full(px.size, i), px.ravel(), py.ravel())
    return out


def _emit(out, cam, xyz, cols, area, tri, px, py):
    """Adds the pixels (px, py) that lie inside their triangle `tri`, with perspective-correct depth and colour."""
    sx, sy = px + 0.5, py + 0.5
    x, y = xyz[:, :, 0], xyz[:, :, 1]
    a = area[tri]
    w0 = ((x[tri, 1] - sx) * (y[tri, 2] - sy) - (x[tri, 2] - sx) * (y[tri, 1] - sy)) / a
    w1 = ((x[tri, 2] - sx) * (y[tri, 0] - sy) - (x[tri, 0] - sx) * (y[tri, 2] - sy)) / a
    w2 = 1 - w0 - w1
    inside = (w0 >= -1e-9) & (w1 >= -1e-9) & (w2 >= -1e-9)
    if not inside.any():
        return
    tri, px, py = tri[inside], px[inside], py[inside]
    bw = np.stack([w0[inside], w1[inside], w2[inside]], 1)
    invz = bw / xyz[tri, :, 2]
    s = invz.sum(1)
    out[0].append(py * cam.width + px)
    out[1].append(1 / s)
    out[2].append(np.einsum("nk,nkc->nc", invz, cols[tri]) / s[:, None])


def _disc_fragments(cam, centres, colours, radius_m):
    p = cam.project(centres)
    ok = np.isfinite(p).all(1)
    p, colours = p[ok], colours[ok]
    if not len(p):
        return [], [], []
    r = np.maximum(cam.focal * radius_m / p[:, 2], 0.7)
    R = int(min(np.ceil(r.max()), 40))
    offs = np.array([(dx, dy) for dx in range(-R, R + 1) for dy in range(-R, R + 1)], float)
    px = np.floor(p[:, None, 0] + offs[None, :, 0]).astype(np.int64)
    py = np.floor(p[:, None, 1] + offs[None, :, 1]).astype(np.int64)
    d2 = (px + 0.5 - p[:, None, 0]) ** 2 + (py + 0.5 - p[:, None, 1]) ** 2
    inside = (d2 <= r[:, None] ** 2) & (px >= 0) & (py >= 0) & (px < cam.width) & (py < cam.height)
    # a sphere's front: nearer at its centre, shaded darker toward its rim
    shade = 1 - 0.45 * d2 / np.maximum(r[:, None] ** 2, 1e-9)
    z = p[:, None, 2] - radius_m * np.sqrt(np.clip(1 - d2 / np.maximum(r[:, None] ** 2, 1e-9), 0, 1))
    c = colours[:, None, :] * shade[..., None]
    return [(py * cam.width + px)[inside]], [z[inside]], [c[inside]]


def _line_fragments(cam, segments, colour, width_px):
    seg = np.asarray(segments, float).reshape(-1, 2, 3)
    if not len(seg):
        return [], [], []
    a, b = cam.project(seg[:, 0]), cam.project(seg[:, 1])
    ok = np.isfinite(a).all(1) & np.isfinite(b).all(1)
    a, b = a[ok], b[ok]
    length = np.linalg.norm(b[:, :2] - a[:, :2], axis=1)
    n = np.maximum(np.ceil(length * 2).astype(int), 1) + 1
    seg_i = np.repeat(np.arange(len(a)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    t = (np.arange(n.sum()) - start) / np.repeat(n - 1, n).clip(1)
    p = a[seg_i] + (b[seg_i] - a[seg_i]) * t[:, None]
    R = max(int(round(width_px / 2)), 0)
    offs = [(dx, dy) for dx in range(-R, R + 1) for dy in range(-R, R + 1) if dx * dx + dy * dy <= R * R + 0.5]
    pix, zs = [], []
    for dx, dy in offs:
        px = np.floor(p[:, 0]).astype(np.int64) + dx
        py = np.floor(p[:, 1]).astype(np.int64) + dy
        inside = (px >= 0) & (py >= 0) & (px < cam.width) & (py < cam.height)
        pix.append((py * cam.width + px)[inside])
        zs.append(p[inside, 2] - 0.002)  # drawn a hair in front of the surface it lies on
    pix, zs = np.concatenate(pix), np.concatenate(zs)
    return [pix], [zs], [np.tile(colour, (len(pix), 1))]


# ---- the picture --------------------------------------------------------------------------------------------

def _mesh_triangles(mesh, cam):
    v = np.asarray(mesh.vertices, float)
    t = np.asarray(mesh.triangles, np.int64)
    if not len(t):
        return np.zeros((0, 3, 3)), np.zeros((0, 3, 3))
    f = cam.basis()[2]
    if mesh.smooth:
        # one view direction (the camera's) for every vertex: at a 35-40 degree field it hardly differs
        cols = _shade(_vertex_normals(v, t), mesh.color, f)[t]
    else:
        n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        cols = np.repeat(_shade(n, mesh.color, f)[:, None, :], 3, axis=1)
    return cam.project(v)[t], cols


def _shadow(frame: Frame, cam: Camera, zbuf: np.ndarray) -> np.ndarray:
    """Per-pixel light factors (1: lit) for the shadow the hands cast straight down (a light overhead) onto the
    body tops under them: each hand triangle is dropped onto the highest top below it and rasterized; it
    darkens the pixels that show that top there. Softened by a small blur, lighter the higher the hand hovers:
    enough to read how far above the table or the box a hand is."""
    factor = np.ones(cam.width * cam.height)
    tops = []
    for m in frame.meshes:
        if m.kind == "body" and len(m.vertices):
            v = np.asarray(m.vertices, float)
            tops.append((v.min(0), v.max(0)))
    for m in frame.meshes:
        if m.kind != "hand" or not tops:
            continue
        v = np.asarray(m.vertices, float)
        ground = np.full(len(v), np.nan)
        for lo, hi in tops:
            over = (v[:, 0] >= lo[0]) & (v[:, 0] <= hi[0]) & (v[:, 2] >= lo[2]) & (v[:, 2] <= hi[2]) & \
                   (v[:, 1] >= hi[1] - 1e-3)
            ground = np.where(over & ~(ground > hi[1]), hi[1], ground)
        ground[ground > cam.position[1] - 0.01] = np.nan  # a top seen from below shows no shadow
        height = v[:, 1] - ground
        drop = v.copy()
        drop[:, 1] = ground + 2e-4
        t = np.asarray(m.triangles, np.int64)
        cols = np.repeat(height[:, None], 3, 1)[t]
        pix, z, c = _triangle_fragments(cam, cam.project(drop)[t], cols, cull=False)
        if not pix:
            continue
        pix, z, h = np.concatenate(pix), np.concatenate(z), np.concatenate(c)[:, 0]
        on_top = np.abs(z - zbuf[pix]) < 0.003  # the pixel shows the top the shadow falls on, not the hand
        strength = np.clip(0.45 - 2.0 * h[on_top], 0.12, 0.45)
        np.minimum.at(factor, pix[on_top], 1 - strength)
    r = max(1, cam.height // 200)
    return _box_blur(factor.reshape(cam.height, cam.width), r).ravel()


def _box_blur(img, r):
    """Mean over a (2r+1)^2 square, edges clamped, by running sums along each axis."""
    out = img
    for axis in (0, 1):
        pad = np.concatenate([np.repeat(out.take([0], axis), r + 1, axis), out,
                              np.repeat(out.take([-1], axis), r, axis)], axis)
        c = np.cumsum(pad, axis)
        n = out.shape[axis]
        out = (c.take(np.arange(2 * r + 1, 2 * r + 1 + n), axis) - c.take(np.arange(0, n), axis)) / (2 * r + 1)
    return out


def render(frame: Frame, camera: Camera, supersample: int = 2, shadows: bool = True, labels: bool = True,
           title: Optional[str] = None, ids: bool = False):
    """An (H, W, 3) uint8 picture of `frame` seen by `camera`. With ``ids=True`` returns instead an (H, W) int
    array naming the mesh each pixel shows (index into frame.meshes, -1: background) at the camera's own
    size: what a test expects a screenshot to show where."""
    k = 1 if ids else max(1, int(supersample))
    cam = camera.scaled(k)
    size = cam.width * cam.height
    pix, zs, cs = [], [], []
    tags = []
    for i, mesh in enumerate(frame.meshes):
        xyz, cols = _mesh_triangles(mesh, cam)
        if ids:
            cols = np.full(cols.shape, float(i))
        p, z, c = _triangle_fragments(cam, xyz, cols, cull=mesh.closed)
        pix += p
        zs += z
        cs += c
    if not ids:
        for pts in frame.points:
            p, z, c = _disc_fragments(cam, pts.positions, np.asarray(pts.colors, float), pts.radius)
            pix += p
            zs += z
            cs += c
        for ln in frame.lines:
            p, z, c = _line_fragments(cam, ln.segments, np.asarray(ln.color, float), ln.width * k * 0.5)
            pix += p
            zs += z
            cs += c
    if ids:
        out = np.full(size, -1, np.int64)
    else:
        yy = np.linspace(0, 1, cam.height)[:, None, None]
        out = (BACKGROUND_TOP * (1 - yy) + BACKGROUND_BOTTOM * yy) * np.ones((1, cam.width, 1))
        out = out.reshape(size, 3)
    if pix:
        pix, zs, cs = np.concatenate(pix), np.concatenate(zs), np.concatenate(cs)
        zbuf = np.full(size, np.inf)
        np.minimum.at(zbuf, pix, zs)
        win = zs <= zbuf[pix]
        if ids:
            out[pix[win]] = np.rint(cs[win, 0]).astype(np.int64)
        else:
            out[pix[win]] = cs[win]
            if shadows:
                out *= _shadow(frame, cam, zbuf)[:, None]
    if ids:
        return out.reshape(cam.height, cam.width)
    img = out.reshape(cam.height, cam.width, 3)
    if k > 1:
        img = img.reshape(camera.height, k, camera.width, k, 3).mean(axis=(1, 3))
    img = (np.clip(img, 0, 1) * 255).astype(np.uint8)
    if (labels and frame.labels) or title:
        img = _annotate(img, frame, camera, title if title else None, labels)
    return img


def _font(size):
    from PIL import ImageFont
    for path in ("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",):
        try:
            return ImageFont.truetype(path, size)
        except OSError:
            pass
    return ImageFont.load_default()


def _annotate(img, frame, camera, title, labels):
    from PIL import Image, ImageDraw
    im = Image.fromarray(img)
    d = ImageDraw.Draw(im)
    font = _font(max(11, camera.height // 38))
    if labels:
        for lab in frame.labels:
            p = camera.project(lab.position)[0]
            if not np.isfinite(p).all():
                continue
            x, y = float(np.clip(p[0], 4, camera.width - 4)), float(np.clip(p[1], 4, camera.height - 4))
            box = d.textbbox((x, y), lab.text, font=font, anchor="mb")
            d.rectangle((box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2), fill=(255, 255, 235), outline=(90, 90, 90))
            d.text((x, y), lab.text, fill=(20, 20, 20), font=font, anchor="mb")
    if title:
        tf = _font(max(12, camera.height // 30))
        d.text((10, 8), title, fill=(15, 15, 15), font=tf)
    return np.asarray(im)


def save_png(img, path):
    from PIL import Image
    from pathlib import Path
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(img).save(path)
    return path
