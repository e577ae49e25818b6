#!/usr/bin/env python3
"""An independent renderer of connector images with exact truth
(shared/spec/vision.md), drawn at random over the whole imaging envelope of
docs/vision.md ("Operating envelope"), every factor at once.

It shares no code and no optics with `pinsight::vision::synth` or
`synth_envelope`: numpy + OpenCV + Pillow, shapes as signed-distance
functions in the part frame whose boundary pixels are supersampled 8 x 8;
a bevelled tip profile with an off-centre glint from a tilted light; a
pillbox/Gaussian/mixed PSF; polynomial vignetting; Poisson-Gaussian noise
with row noise; JPEG by OpenCV (grey) or Pillow (colour, 4:2:0).

    python3 tests/python/connector_render.py OUT_DIR FIRST_SEED N

writes OUT_DIR/py-SEED.{png|jpg|tif}, .json (truth, with a "factors"
object) and .toml (the recipe) per seed. Seeds 500000-500999 are the
held-out set nobody tunes on (docs/vision.md).
"""
import json
import math
import os
import sys

import cv2
import numpy as np
from PIL import Image

SUB = 8  # subsamples per pixel side on boundary pixels


# ---------------------------------------------------------------- shapes
def sdf_rrect(u, v, hx, hy, r):
    qx = np.abs(u) - (hx - r)
    qy = np.abs(v) - (hy - r)
    out = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0))
    return out + np.minimum(np.maximum(qx, qy), 0) - r


def sdf_poly(u, v, pts):
    """Signed distance to a closed polygon (negative inside), even-odd."""
    d = np.full(u.shape, np.inf)
    inside = np.zeros(u.shape, bool)
    n = len(pts)
    for i in range(n):
        ax, ay = pts[i]
        bx, by = pts[(i + 1) % n]
        ex, ey = bx - ax, by - ay
        wx, wy = u - ax, v - ay
        t = np.clip((wx * ex + wy * ey) / (ex * ex + ey * ey), 0, 1)
        d = np.minimum(d, np.hypot(wx - t * ex, wy - t * ey))
        cond = ((ay > v) != (by > v)) & (u < ax + (v - ay) * ex / (ey + 1e-300))
        inside ^= cond
    return np.where(inside, -d, d)


class Frame:
    """Pixel <-> part frame (mm): x = cx + (cos r u - sin r v)/s, ..."""

    def __init__(self, cx, cy, rot, mmpp):
        self.cx, self.cy, self.c, self.s, self.m = cx, cy, math.cos(rot), math.sin(rot), mmpp

    def to_px(self, u, v):
        return (self.cx + (self.c * u - self.s * v) / self.m,
                self.cy + (self.s * u + self.c * v) / self.m)

    def to_mm(self, x, y):
        dx, dy = x - self.cx, y - self.cy
        return ((self.c * dx + self.s * dy) * self.m, (-self.s * dx + self.c * dy) * self.m)


def coverage(fr, sdf, bbox, shape):
    """Coverage of the shape (sdf in mm of (u, v)) per pixel in bbox
    (x0, y0, x1, y1 in px, clipped to the image); also the sdf at pixel
    centres (mm). Returns (y0, x0, cov, d) or None when off the image."""
    h, w = shape
    x0, y0 = max(int(math.floor(bbox[0])) - 2, 0), max(int(math.floor(bbox[1])) - 2, 0)
    x1, y1 = min(int(math.ceil(bbox[2])) + 3, w), min(int(math.ceil(bbox[3])) + 3, h)
    if x1 <= x0 or y1 <= y0:
        return None
    ys, xs = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    u, v = fr.to_mm(xs, ys)
    d = sdf(u, v)
    cov = (d < 0).astype(np.float64)
    edge = np.abs(d) < 0.75 * fr.m
    if edge.any():
        ey, ex = np.nonzero(edge)
        off = (np.arange(SUB) + 0.5) / SUB - 0.5
        oy, ox = np.meshgrid(off, off, indexing="ij")
        px = xs[ey, ex][:, None] + ox.ravel()[None, :]
        py = ys[ey, ex][:, None] + oy.ravel()[None, :]
        su, sv = fr.to_mm(px, py)
        cov[ey, ex] = (sdf(su, sv) < 0).mean(axis=1)
    return y0, x0, cov, d


def paint(canvas, patch, level):
    """canvas <- lerp(canvas, level, coverage); level scalar or array."""
    if patch is None:
        return
    y0, x0, cov, _ = patch
    sl = canvas[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
    sl += cov * (level - sl)


def bbox_of(fr, us, vs, pad_mm):
    xs, ys = [], []
    for u in (min(us) - pad_mm, max(us) + pad_mm):
        for v in (min(vs) - pad_mm, max(vs) + pad_mm):
            x, y = fr.to_px(u, v)
            xs.append(x)
            ys.append(y)
    return (min(xs), min(ys), max(xs), max(ys))


def smooth_field(rng, shape, sigma):
    """Zero-mean, unit-std smooth random field (computed at a reduced size
    for large sigma, then resized)."""
    h, w = shape
    k = max(1, int(sigma / 3))
    small = rng.standard_normal((h // k + 2, w // k + 2)).astype(np.float32)
    small = cv2.GaussianBlur(small, (0, 0), max(sigma / k, 0.5))
    f = cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)
    return (f - f.mean()) / (f.std() + 1e-9)


# ---------------------------------------------------------------- draws
def u01(rng, a, b):
    return float(rng.uniform(a, b))


def draw_recipe(rng, seed):
    view = "side" if rng.random() < 0.25 else "top"
    rows = 1 if view == "side" else int(rng.choice([1, 1, 2, 2, 2, 3, 4]))
    cols = int(rng.integers(2, 21))
    px_ = u01(rng, 1.0, 3.0)
    py_ = px_ if rng.random() < 0.6 else px_ * u01(rng, 0.8, 1.4)
    shape = "round" if (view == "top" and rng.random() < 0.4) else "square"
    pin = min(px_, py_) * u01(rng, 0.2, 0.42)
    pol = "dark" if view == "side" else ("dark" if rng.random() < 0.45 else "bright")
    return dict(view=view, rows=rows, cols=cols, pitch=[px_, py_], pin=pin, shape=shape,
                polarity=pol, part=f"PY-{view[0].upper()}{rows}x{cols}-{seed}")


def draw_case(seed):
    rng = np.random.default_rng(seed)
    for _ in range(200):
        r = draw_recipe(rng, seed)
        mmpp = math.exp(u01(rng, math.log(0.008), math.log(0.05)))
        if r["pin"] / mmpp < 4.0:
            continue
        px_, py_ = r["pitch"]
        if r["view"] == "top":
            margin = u01(rng, 0.45, 1.0) * max(px_, py_)
            ext_u = (r["cols"] - 1) * px_ / 2 + margin
            ext_v = (r["rows"] - 1) * py_ / 2 + margin
            need_w = 2 * ext_u / mmpp + 2 * 1.3 * px_ / mmpp
            need_h = 2 * ext_v / mmpp + 2 * 1.3 * px_ / mmpp
        else:
            margin = u01(rng, 0.4, 1.2) * px_
            ext_u = (r["cols"] - 1) * px_ / 2 + margin
            need_w = 2 * ext_u / mmpp + 20
            need_h = (4.5 + 1.5 + 1.5) / mmpp
            ext_v = 0
        rot = math.radians(u01(rng, -5, 5))
        need_w2 = need_w * abs(math.cos(rot)) + need_h * abs(math.sin(rot))
        need_h2 = need_w * abs(math.sin(rot)) + need_h * abs(math.cos(rot))
        aspect = u01(rng, 1.0, 3.0)
        portrait = rng.random() < 0.2
        # smallest image of this aspect holding the part
        if portrait:
            w = max(240, need_w2, need_h2 / aspect)
            h = w * aspect
            h = max(h, 320, need_h2)
        else:
            w = max(320, need_w2)
            h = max(240, need_h2, w / aspect)
            w = max(w, h * aspect) if h * aspect < 4e4 else w
        if w * h > 5.0e6:
            continue
        grow = math.sqrt(min(5.0e6 / (w * h), math.exp(u01(rng, 0, math.log(4.0)))))
        w, h = int(w * grow), int(h * grow)
        if w * h > 5.0e6 or w < 320 and h < 320:
            continue
        return rng, r, mmpp, rot, w, h, ext_u, ext_v, margin
    raise RuntimeError("no draw fits")


def main():
    out, first, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    os.makedirs(out, exist_ok=True)
    for seed in range(first, first + n):
        render_one(out, seed)


def render_one(out, seed):
    rng, r, mmpp, rot, W, H, ext_u, ext_v, margin = draw_case(seed)
    top = r["view"] == "top"
    px_, py_ = r["pitch"]
    tipw = r["pin"]
    f = dict(seed=seed, view=r["view"], polarity=r["polarity"], pin_shape=r["shape"], rows=r["rows"],
             cols=r["cols"], width=W, height=H, mm_per_px=mmpp, tip_px=tipw / mmpp,
             rotation_deg=math.degrees(rot), aspect=max(W, H) / min(W, H), megapixels=W * H / 1e6)
    f["contrast"] = u01(rng, 0.3, 1.0)
    f["noise_dn"] = u01(rng, 0.0, 16.0)
    f["blur_px"] = u01(rng, 0.0, 2.5)
    f["psf"] = str(rng.choice(["pillbox", "gauss", "mixed"]))
    f["vignetting"] = u01(rng, 0.0, 0.5)
    f["gradient"] = u01(rng, 0.0, 0.2)
    f["gain"] = u01(rng, 0.6, 1.3)
    f["texture_dn"] = u01(rng, 0.5, 6.0)
    f["bits"] = int(rng.choice([8, 8, 8, 12, 16]))
    f["colour"] = bool(rng.random() < 0.25)
    f["jpeg_quality"] = int(rng.integers(50, 101)) if (f["bits"] == 8 and rng.random() < 0.35) else None
    f["scale_in_recipe"] = bool(rng.random() < 0.5)
    # Tolerance band: at least 3.5 px at this scale, at most 0.18 pitch.
    pos_tol = max(u01(rng, 0.05, 0.15), 3.5 * mmpp)
    pos_tol = min(pos_tol, 0.18 * min(px_, py_))
    if pos_tol < 3.2 * mmpp:
        pos_tol = 3.2 * mmpp
    # Pose: the part anywhere in the image.
    c, s = math.cos(rot), math.sin(rot)
    if top:
        hu, hv = ext_u / mmpp, ext_v / mmpp
        bx = abs(c) * hu + abs(s) * hv + 1.3 * px_ / mmpp
        by = abs(s) * hu + abs(c) * hv + 1.3 * px_ / mmpp
        # int() above can cut the frame a pixel below what the part needs:
        # then the part sits centred (an empty range crashed seed 550 342).
        cx, cy = u01(rng, bx, max(bx, W - 1 - bx)), u01(rng, by, max(by, H - 1 - by))
    else:
        hu = ext_u / mmpp
        cx = u01(rng, abs(c) * hu + 10, W - 1 - abs(c) * hu - 10)
        cy = u01(rng, 4.5 / mmpp + 1.0 / mmpp, H - 1 - 1.2 / mmpp)
    fr = Frame(cx, cy, rot, mmpp)
    f["pose"] = dict(cx=cx, cy=cy, rotation_deg=math.degrees(rot))
    canvas = np.zeros((H, W), np.float64)
    tex = f["texture_dn"]
    kinds = []
    pins, extras = [], []
    recipe = dict(part_number=r["part"], view=r["view"], rows=r["rows"], cols=r["cols"],
                  pitch_mm=[round(px_, 6), round(py_, 6)], pin_mm=round(tipw, 6), pin_shape=r["shape"],
                  polarity=r["polarity"])
    if f["scale_in_recipe"]:
        recipe["mm_per_px"] = mmpp
    tol = dict(position_mm=round(pos_tol, 6))
    skip = []
    if top:
        render_top(rng, f, fr, canvas, r, tipw, pos_tol, ext_u, ext_v, tex, pins, extras, kinds, skip)
        tol["tip_area"] = [0.6, 1.5]
    else:
        hn, htol = render_side(rng, f, fr, canvas, r, tipw, pos_tol, ext_u, tex, pins, extras, kinds)
        tol["height_mm"] = round(hn, 6)
        tol["height_tol_mm"] = round(htol, 6)
    if skip:
        recipe["skip"] = skip
    f["defects"] = sorted(set(kinds))
    img = finish(rng, f, canvas)
    stem = f"py-{seed:06d}"
    if f["jpeg_quality"] is not None:
        path = f"{stem}.jpg"
        q = f["jpeg_quality"]
        if img.ndim == 3:
            Image.fromarray(img).save(os.path.join(out, path), quality=q, subsampling=2)
        else:
            ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, q])
            buf.tofile(os.path.join(out, path))
    else:
        ext = ".tif" if (seed % 7 == 3) else ".png"
        path = stem + ext
        wr = img[:, :, ::-1] if img.ndim == 3 else img  # OpenCV writes BGR
        cv2.imwrite(os.path.join(out, path), wr)
    verdict = "pass" if all(p["defect"] == "ok" for p in pins) and not extras else "fail"
    truth = dict(recipe=stem + ".toml", mm_per_px=mmpp, verdict=verdict, pins=pins, extras=extras,
                 view=r["view"], part_number=r["part"], image=path, factors=f)
    with open(os.path.join(out, stem + ".json"), "w") as fh:
        json.dump(truth, fh, indent=1)
    with open(os.path.join(out, stem + ".toml"), "w") as fh:
        fh.write(to_toml(recipe, tol))


def to_toml(rec, tol):
    lines = []
    for k, v in rec.items():
        if isinstance(v, str):
            lines.append(f'{k} = "{v}"')
        elif isinstance(v, list):
            lines.append(f"{k} = {json.dumps(v)}")
        else:
            lines.append(f"{k} = {v!r}")
    lines.append("")
    lines.append("[tolerance]")
    for k, v in tol.items():
        lines.append(f"{k} = {json.dumps(v)}")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- top view
def seed_of(f):
    return f["seed"]


def render_top(rng, f, fr, canvas, r, tipw, pos_tol, ext_u, ext_v, tex, pins, extras, kinds, skip):
    H, W = canvas.shape
    px_, py_ = r["pitch"]
    rows, cols = r["rows"], r["cols"]
    bright = r["polarity"] == "bright"
    con = 140.0 * f["contrast"]
    # Scene levels (8-bit DN before gain and illumination).
    if bright:
        housing = u01(rng, 35, 85)
        fixture = u01(rng, 10, 110)
        hole = housing * u01(rng, 0.15, 0.55)
        tip_top = housing + con
        tip_rim = housing + con * u01(rng, 0.55, 0.85)
        mark = housing + con * u01(rng, 0.08, 0.2)
    else:
        housing = u01(rng, 150, 215)
        fixture = u01(rng, 30, 250)
        hole = min(housing + u01(rng, 15, 45), 252)
        tip_top = max(housing - con, 4.0)
        tip_rim = housing - (housing - tip_top) * u01(rng, 0.7, 0.95)
        mark = housing - con * u01(rng, 0.08, 0.2)
    f["levels"] = dict(housing=housing, fixture=fixture, hole=hole, tip=tip_top)
    # Fixture: textured plate with a few machining grooves.
    canvas[:] = fixture + tex * 1.5 * smooth_field(rng, (H, W), u01(rng, 4, 20))
    for _ in range(int(rng.integers(0, 4))):
        ang = u01(rng, 0, math.pi)
        off = u01(rng, -0.5, 0.5) * max(W, H)
        ys, xs = np.mgrid[0:H, 0:W]
        dist = (xs - W / 2) * math.sin(ang) - (ys - H / 2) * math.cos(ang) - off
        canvas += -np.sign(fixture - 60) * tex * 2 * np.exp(-0.5 * (dist / 1.2) ** 2)
    # Housing: rounded rectangle, chamfered rim, texture.
    hr = u01(rng, 0.05, 0.3) * min(ext_u, ext_v)
    bb = bbox_of(fr, [-ext_u, ext_u], [-ext_v, ext_v], 0.1)
    ph = coverage(fr, lambda u, v: sdf_rrect(u, v, ext_u, ext_v, hr), bb, canvas.shape)
    y0, x0, cov, d = ph
    cham = u01(rng, 0.05, 0.2)
    rim = u01(rng, -0.25, 0.15) * housing
    lvl = housing + rim * np.clip(1 + d / cham, 0, 1)
    lvl = lvl + tex * smooth_field(rng, cov.shape, u01(rng, 1.5, 6)) + 0.5 * tex * rng.standard_normal(cov.shape)
    paint(canvas, (y0, x0, cov, d), lvl)
    # Orientation mark near pin (0, 0), outside the pin field.
    u00 = -(cols - 1) / 2 * px_
    v00 = -(rows - 1) / 2 * py_
    mu, mv = u00 - 0.0, v00 - 0.5 * py_ - 0.0
    mr = 0.18 * min(px_, py_)
    if ext_v > abs(mv) + mr and rng.random() < 0.7:
        paint(canvas, coverage(fr, lambda u, v: np.hypot(u - mu, v - mv) - mr,
                               bbox_of(fr, [mu], [mv], mr + 0.05), canvas.shape), mark)
    # Positions, defects.
    all_pos = [(i, j) for i in range(rows) for j in range(cols)]
    if rng.random() < 0.15 and len(all_pos) > 3:
        k = tuple(all_pos[int(rng.integers(len(all_pos)))])
        # never a corner: keep the grid placeable from the pins
        if k not in [(0, 0), (0, cols - 1), (rows - 1, 0), (rows - 1, cols - 1)]:
            skip.append([k[0], k[1]])
    live = [p for p in all_pos if [p[0], p[1]] not in skip]
    defect = {p: "ok" for p in live}
    n_def = 0 if rng.random() < 0.45 else int(rng.choice([1, 1, 1, 2, 2, 3]))
    for _ in range(n_def):
        kind = str(rng.choice(["missing", "bent", "damaged", "extra"], p=[0.25, 0.3, 0.25, 0.2]))
        if kind == "extra":
            kinds.append("extra")
            continue
        p = live[int(rng.integers(len(live)))]
        if defect[p] != "ok":
            continue
        if kind == "missing":
            # never a whole end column empty (the grid must be placeable)
            colp = [q for q in live if q[1] == p[1] and q != p]
            if (p[1] in (0, cols - 1)) and all(defect[q] == "missing" for q in colp):
                continue
        defect[p] = kind
        kinds.append(kind)
    shape = r["shape"]
    hole_w = tipw * u01(rng, 1.3, 1.7)
    bevel = tipw * u01(rng, 0.1, 0.25)
    corner = tipw * u01(rng, 0.03, 0.2)
    glint_dir = u01(rng, 0, 2 * math.pi)
    glint_off = tipw * u01(rng, 0.0, 0.12)
    glint_amp = con * u01(rng, 0.0, 0.35) * (1 if bright else 0)
    glint_r = tipw * u01(rng, 0.12, 0.25)
    nom_area = tipw * tipw if shape == "square" else math.pi * tipw * tipw / 4
    for (i, j) in live:
        nu = (j - (cols - 1) / 2) * px_
        nv = (i - (rows - 1) / 2) * py_
        # clearance hole at the nominal position
        if shape == "square":
            hsdf = (lambda u, v, nu=nu, nv=nv: sdf_rrect(u - nu, v - nv, hole_w / 2, hole_w / 2, 0.2 * hole_w))
        else:
            hsdf = (lambda u, v, nu=nu, nv=nv: np.hypot(u - nu, v - nv) - hole_w / 2)
        paint(canvas, coverage(fr, hsdf, bbox_of(fr, [nu], [nv], hole_w), canvas.shape), hole)
        kind = defect[(i, j)]
        if kind == "missing":
            pins.append(dict(row=i, col=j, x_px=None, y_px=None, defect="missing"))
            continue
        if kind == "bent":
            mag = pos_tol * u01(rng, 1.2, 2.6)
            mag = min(mag, 0.3 * min(px_, py_))
            if mag < 1.15 * pos_tol:
                defect[(i, j)] = kind = "ok"
                mag = 0.0
        else:
            mag = pos_tol * min(abs(rng.normal(0, 0.3)), 0.8)
        ang = u01(rng, 0, 2 * math.pi)
        cu, cv_ = nu + mag * math.cos(ang), nv + mag * math.sin(ang)
        twist = math.radians(u01(rng, -4, 4))
        scale = 1.0 if kind != "damaged" else 0.0
        area_target = u01(rng, 0.92, 1.08)
        chip = None
        if kind == "damaged":
            dk = str(rng.choice(["shrunk", "enlarged", "chipped"]))
            if dk == "shrunk":
                area_target = u01(rng, 0.25, 0.5)
            elif dk == "enlarged":
                area_target = u01(rng, 1.7, 2.3)
            else:
                area_target = 1.0
                chip = (u01(rng, 0, 2 * math.pi), u01(rng, -0.2, -0.02) * tipw)
            scale = math.sqrt(area_target)
        else:
            scale = math.sqrt(area_target)
        hw = tipw / 2 * scale
        ct, st = math.cos(twist), math.sin(twist)

        def tsdf(u, v, cu=cu, cv_=cv_, hw=hw, ct=ct, st=st, chip=chip):
            a, b = u - cu, v - cv_
            a, b = ct * a + st * b, -st * a + ct * b
            if shape == "square":
                dd = sdf_rrect(a, b, hw, hw, min(corner, 0.9 * hw))
            else:
                dd = np.hypot(a, b) - hw
            if chip is not None:
                # a half-plane bites one side off: keep n.(p) <= c
                nx, ny = math.cos(chip[0]), math.sin(chip[0])
                dd = np.maximum(dd, a * nx + b * ny - chip[1])
            return dd

        patch = coverage(fr, tsdf, bbox_of(fr, [cu], [cv_], hw * 1.5 + 0.05), canvas.shape)
        if patch is None:
            continue
        y0, x0, cov, d = patch
        prof = tip_rim + (tip_top - tip_rim) * np.clip(-d / bevel, 0, 1)
        if glint_amp > 0:
            ys, xs = np.mgrid[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
            gu, gv = fr.to_mm(xs.astype(float), ys.astype(float))
            gx = gu - cu - glint_off * math.cos(glint_dir)
            gy = gv - cv_ - glint_off * math.sin(glint_dir)
            prof = prof + glint_amp * np.exp(-0.5 * (gx * gx + gy * gy) / glint_r ** 2) * (d < 0)
        paint(canvas, patch, prof)
        # truth: area centroid of the coverage (exact for symmetric tips)
        ys, xs = np.mgrid[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
        area_px = cov.sum()
        area_ratio = area_px * fr.m * fr.m / nom_area
        if kind == "damaged" or chip is not None:
            tx, ty = float((cov * xs).sum() / area_px), float((cov * ys).sum() / area_px)
        else:
            tx, ty = fr.to_px(cu, cv_)
        # guard band: every label at least 0.05 from the tip_area limits
        assert (kind == "damaged") == (not 0.65 <= area_ratio <= 1.45), (seed_of(f), kind, area_ratio)
        pins.append(dict(row=i, col=j, x_px=round(float(tx), 4), y_px=round(float(ty), 4), defect=kind,
                         offset_mm=round(mag, 5), area_ratio=round(float(area_ratio), 4)))
    # Extras: debris on the housing between pins, or just beside it.
    nx = kinds.count("extra")
    for _ in range(nx):
        for _try in range(50):
            if rng.random() < 0.6:
                eu = (int(rng.integers(0, cols)) - (cols - 1) / 2 + 0.5 * rng.choice([-1, 1])) * px_
                ev = (int(rng.integers(0, rows)) - (rows - 1) / 2 + 0.5 * rng.choice([-1, 1])) * py_
                if rows == 1:
                    ev = rng.choice([-1, 1]) * u01(rng, 0.45, 0.5 + ext_v / py_ * 0.6) * py_
            else:
                side = rng.choice([-1, 1])
                if rng.random() < 0.5:
                    eu = side * (ext_u + u01(rng, 0.1, 0.7) * px_)
                    ev = u01(rng, -ext_v, ext_v)
                else:
                    eu = u01(rng, -ext_u, ext_u)
                    ev = side * (ext_v + u01(rng, 0.1, 0.7) * px_)
            # at least 0.42 pitch from every node of the infinite grid
            gu = (eu / px_ + (cols - 1) / 2) % 1.0
            gv = (ev / py_ + (rows - 1) / 2) % 1.0
            if min(gu, 1 - gu) * px_ < 0.42 * px_ and min(gv, 1 - gv) * py_ < 0.42 * py_:
                continue
            ex, ey = fr.to_px(eu, ev)
            if not (8 < ex < W - 9 and 8 < ey < H - 9):
                continue
            break
        else:
            continue
        area_t = u01(rng, 0.4, 2.3) * nom_area
        nv_ = int(rng.integers(6, 11))
        angs = np.sort(rng.uniform(0, 2 * math.pi, nv_))
        rad = np.sqrt(area_t / math.pi) * rng.uniform(0.7, 1.3, nv_)
        poly = [(eu + rr * math.cos(a), ev + rr * math.sin(a)) for a, rr in zip(angs, rad)]
        dlevel = tip_top * u01(rng, 0.8, 1.0) if bright else tip_top + (housing - tip_top) * u01(rng, 0, 0.2)
        patch = coverage(fr, lambda u, v, poly=poly: sdf_poly(u, v, poly),
                         bbox_of(fr, [p[0] for p in poly], [p[1] for p in poly], 0.05), canvas.shape)
        y0, x0, cov, d = patch
        a_px = cov.sum()
        if a_px * fr.m ** 2 / nom_area < 0.33:
            continue
        paint(canvas, patch, dlevel)
        ys, xs = np.mgrid[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
        extras.append(dict(x_px=round(float((cov * xs).sum() / a_px), 3), y_px=round(float((cov * ys).sum() / a_px), 3),
                           kind="debris", area_ratio=round(float(a_px * fr.m ** 2 / nom_area), 3)))
    if nx and not extras:
        kinds.remove("extra")
    # Fine dust: specks under a tenth of a tip (never an extra).
    for _ in range(int(rng.integers(0, 4))):
        eu, ev = u01(rng, -ext_u, ext_u), u01(rng, -ext_v, ext_v)
        rr = math.sqrt(u01(rng, 0.02, 0.08) * nom_area / math.pi)
        paint(canvas, coverage(fr, lambda u, v, eu=eu, ev=ev, rr=rr: np.hypot(u - eu, v - ev) - rr,
                               bbox_of(fr, [eu], [ev], rr + 0.05), canvas.shape),
              tip_rim if bright else tip_top)


# ---------------------------------------------------------------- side view
def render_side(rng, f, fr, canvas, r, tipw, pos_tol, ext_u, tex, pins, extras, kinds):
    H, W = canvas.shape
    px_ = r["pitch"][0]
    cols = r["cols"]
    con = 140.0 * f["contrast"]
    back = u01(rng, 150, 235)
    sil = max(back - con * u01(rng, 1.0, 1.35), 3.0)
    f["levels"] = dict(backlight=back, silhouette=sil)
    canvas[:] = back * (1 + 0.04 * smooth_field(rng, (H, W), u01(rng, 20, 60))) + 0.4 * tex * smooth_field(
        rng, (H, W), 3)
    hn = u01(rng, 1.5, 4.0)
    htol = max(u01(rng, 0.06, 0.15), 3.5 * fr.m)
    depth = u01(rng, 0.8, 3.0)
    # housing block
    ph = coverage(fr, lambda u, v: sdf_rrect(u, v - depth / 2, ext_u, depth / 2, 0.02),
                  bbox_of(fr, [-ext_u, ext_u], [0, depth], 0.1), canvas.shape)
    y0, x0, cov, d = ph
    paint(canvas, ph, sil + u01(rng, -3, 8) + tex * smooth_field(rng, cov.shape, 3))
    defect = {j: "ok" for j in range(cols)}
    n_def = 0 if rng.random() < 0.45 else int(rng.choice([1, 1, 2, 2, 3]))
    for _ in range(n_def):
        kind = str(rng.choice(["missing", "short", "high", "bent", "extra"], p=[0.2, 0.25, 0.2, 0.15, 0.2]))
        if kind == "extra":
            kinds.append(kind)
            continue
        j = int(rng.integers(cols))
        if defect[j] != "ok" or (kind == "missing" and j in (0, cols - 1)):
            continue
        defect[j] = kind
        kinds.append(kind)
    tip_kind = str(rng.choice(["flat", "chamfer", "round"]))
    ch = tipw * u01(rng, 0.1, 0.3)
    for j in range(cols):
        nu = (j - (cols - 1) / 2) * px_
        kind = defect[j]
        if kind == "missing":
            pins.append(dict(row=0, col=j, x_px=None, y_px=None, defect="missing"))
            continue
        off = 0.0
        h = hn + htol * u01(rng, -0.75, 0.75)
        if kind == "bent":
            off = pos_tol * u01(rng, 1.2, 2.5) * rng.choice([-1, 1])
            off = math.copysign(min(abs(off), 0.3 * px_), off)
            if abs(off) < 1.15 * pos_tol:
                kind = defect[j] = "ok"
        elif kind == "short":
            h = hn - htol * u01(rng, 1.2, 4.0)
        elif kind == "high":
            h = hn + htol * u01(rng, 1.2, 4.0)
        else:
            off = pos_tol * u01(rng, -0.75, 0.75) * 0.5
        cu = nu + off
        hw = tipw / 2
        if tip_kind == "round":
            psdf = (lambda u, v, cu=cu, h=h: sdf_rrect(u - cu, v - (0.3 - h) / 2, hw, (h + 0.3) / 2, 0.999 * hw))
        elif tip_kind == "chamfer":
            poly = [(cu - hw, 0.3), (cu - hw, -h + ch), (cu - hw + ch, -h), (cu + hw - ch, -h), (cu + hw, -h + ch),
                    (cu + hw, 0.3)]
            psdf = (lambda u, v, poly=poly: sdf_poly(u, v, poly))
        else:
            psdf = (lambda u, v, cu=cu, h=h: sdf_rrect(u - cu, v - (0.3 - h) / 2, hw, (h + 0.3) / 2, 0.01 * hw))
        paint(canvas, coverage(fr, psdf, bbox_of(fr, [cu - hw, cu + hw], [-h, 0.3], 0.05), canvas.shape),
              sil + u01(rng, -2, 2))
        tx, ty = fr.to_px(cu, -h)
        pins.append(dict(row=0, col=j, x_px=round(tx, 4), y_px=round(ty, 4), defect=kind,
                         height_mm=round(h, 5), offset_mm=round(abs(off), 5)))
    nom_area = tipw * tipw
    nx = kinds.count("extra")
    for _ in range(nx):
        for _try in range(50):
            eu = u01(rng, -ext_u - 0.3 * px_, ext_u + 0.3 * px_)
            ev = -u01(rng, 0.3, hn + 1.0)
            gu = ((eu / px_ + (cols - 1) / 2) % 1.0)
            if min(gu, 1 - gu) * px_ < tipw * 1.6 and ev > -(hn + 0.5):
                continue
            ex, ey = fr.to_px(eu, ev)
            if 8 < ex < W - 9 and 8 < ey < H - 9:
                break
        else:
            continue
        area_t = u01(rng, 0.45, 2.0) * nom_area
        nv_ = int(rng.integers(6, 11))
        angs = np.sort(rng.uniform(0, 2 * math.pi, nv_))
        rad = np.sqrt(area_t / math.pi) * rng.uniform(0.75, 1.25, nv_)
        poly = [(eu + rr * math.cos(a), ev + rr * math.sin(a)) for a, rr in zip(angs, rad)]
        opac = u01(rng, 0.85, 1.0)
        patch = coverage(fr, lambda u, v, poly=poly: sdf_poly(u, v, poly),
                         bbox_of(fr, [p[0] for p in poly], [p[1] for p in poly], 0.05), canvas.shape)
        y0, x0, cov, d = patch
        a_px = cov.sum()
        if a_px * opac * fr.m ** 2 / nom_area < 0.35:
            continue
        sl = canvas[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
        sl += opac * cov * (sil - sl)
        ys, xs = np.mgrid[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
        extras.append(dict(x_px=round(float((cov * xs).sum() / a_px), 3), y_px=round(float((cov * ys).sum() / a_px), 3),
                           kind="dust", area_ratio=round(float(a_px * fr.m ** 2 / nom_area), 3)))
    if nx and not extras:
        kinds.remove("extra")
    return hn, htol


# ---------------------------------------------------------------- optics, sensor
def finish(rng, f, canvas):
    H, W = canvas.shape
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32)
    # Illumination: polynomial vignetting about an off-centre point, linear gradient.
    vx, vy = W / 2 + u01(rng, -0.25, 0.25) * W, H / 2 + u01(rng, -0.25, 0.25) * H
    rmax = max(math.hypot(vx - a, vy - b) for a in (0, W) for b in (0, H))
    p = u01(rng, 2.0, 4.0)
    f["vignetting_power"] = p
    rr = np.hypot(xs - vx, ys - vy) / rmax
    illum = 1.0 - f["vignetting"] * rr ** p
    ga = u01(rng, 0, 2 * math.pi)
    span = abs(math.cos(ga)) * W + abs(math.sin(ga)) * H
    illum *= 1.0 + f["gradient"] * (((xs - W / 2) * math.cos(ga) + (ys - H / 2) * math.sin(ga)) / span)
    img = (canvas * illum * f["gain"]).astype(np.float32)
    del xs, ys, rr, illum
    # PSF with the drawn RMS width (per axis).
    sig = f["blur_px"]
    if sig > 0.05:
        kind = f["psf"]
        if kind == "gauss":
            img = cv2.GaussianBlur(img, (0, 0), sig)
        else:
            # pillbox of radius R has per-axis sigma R/2
            ps = sig if kind == "pillbox" else sig * 0.8
            R = 2.0 * ps
            n = int(math.ceil(R)) + 1
            yy, xx = np.mgrid[-n:n + 1, -n:n + 1].astype(np.float64)
            k = np.zeros_like(xx)
            off = (np.arange(8) + 0.5) / 8 - 0.5
            for oy in off:
                for ox in off:
                    k += (np.hypot(xx + ox, yy + oy) <= R)
            if k.sum() == 0:
                # A disc narrower than the 1/8-pixel sampling: a point.
                k[n, n] = 1.0
            k /= k.sum()
            img = cv2.filter2D(img, -1, k.astype(np.float32), borderType=cv2.BORDER_REFLECT)
            if kind == "mixed":
                img = cv2.GaussianBlur(img, (0, 0), sig * 0.6)
    # Sensor: Poisson-Gaussian noise drawn to total sigma at mid-grey, row noise.
    sd = f["noise_dn"]
    shot_frac = u01(rng, 0.2, 0.9)
    k_shot = shot_frac * sd * sd / 128.0
    read = math.sqrt(max(sd * sd * (1 - shot_frac), 0.0))
    nch = 3 if f["colour"] else 1
    tint = [1.0, 1.0, 1.0]
    if f["colour"]:
        tint = [u01(rng, 0.85, 1.1), 1.0, u01(rng, 0.8, 1.15)]
        luma = 0.2126 * tint[0] + 0.7152 * tint[1] + 0.0722 * tint[2]
        tint = [t / luma for t in tint]
    full = {8: 255.0, 12: 4095.0, 16: 65535.0}[f["bits"]]
    chans = []
    for ch in range(nch):
        x = np.clip(img * tint[ch], 0, None)
        if sd > 0:
            var = read * read + k_shot * x
            x = x + np.sqrt(var) * rng.standard_normal(x.shape).astype(np.float32)
            x = x + 0.15 * sd * rng.standard_normal((H, 1)).astype(np.float32)
        x = np.clip(x * (full / 255.0), 0, full)
        chans.append(np.rint(x).astype(np.uint8 if f["bits"] == 8 else np.uint16))
    return chans[0] if nch == 1 else np.stack(chans, axis=2)


if __name__ == "__main__":
    main()
