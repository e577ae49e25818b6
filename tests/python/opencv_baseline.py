#!/usr/bin/env python3
"""The plain OpenCV pipeline issue 12 compares pinsight with: white top-hat,
Otsu, connected components, a RANSAC grid fit; per nominal position the
nearest blob (missing / damaged by area / bent by offset), unassigned blobs
near the grid are extras. Side view: Otsu silhouette, a RANSAC line through
the column tops for the housing edge, bars above it, the tip by the
half-level crossing on the bar's axis.

It is a reference for comparison, written the way a vision engineer would
write it in an afternoon; it is not tuned on any set.

    python3 tests/python/opencv_baseline.py IMAGE RECIPE.toml   -> JSON on stdout
"""
import json
import math
import sys

import cv2
import numpy as np

try:
    import tomllib
except ImportError:  # Python < 3.11
    import tomli as tomllib


def load_gray(path):
    im = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if im is None:
        raise ValueError(f"cannot read {path}")
    full = 255.0 if im.dtype == np.uint8 else (4095.0 if im.max() <= 4095 else 65535.0)
    im = im.astype(np.float32)
    if im.ndim == 3:
        b, g, r = im[:, :, 0], im[:, :, 1], im[:, :, 2]
        im = 0.2126 * r + 0.7152 * g + 0.0722 * b
    return im / full


def blobs_at(g, tip):
    # denoise at a fraction of the tip, then a white top-hat of 2.5 tips
    g = cv2.GaussianBlur(g, (0, 0), max(0.8, tip / 8))
    k = int(round(2.5 * tip)) | 1
    se = cv2.getStructuringElement(cv2.MORPH_RECT, (k, k))
    th = cv2.morphologyEx(g, cv2.MORPH_TOPHAT, se)
    t8 = np.clip(th / max(float(th.max()), 1e-6) * 255, 0, 255).astype(np.uint8)
    otsu, _ = cv2.threshold(t8, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    # Otsu splits the background's own texture when the tips are a small
    # fraction of the pixels: never below the noise floor (median + 6 MAD).
    med = float(np.median(t8))
    mad = float(np.median(np.abs(t8.astype(np.float32) - med)))
    thr = max(otsu, med + 6 * 1.4826 * mad)
    bw = (t8 > thr).astype(np.uint8)
    n, lab, st, cen = cv2.connectedComponentsWithStats(bw, connectivity=8)
    out = []
    for i in range(1, n):
        a = st[i, cv2.CC_STAT_AREA]
        if a >= 0.1 * tip * tip and a <= 5 * tip * tip:
            out.append((cen[i][0], cen[i][1], float(a)))
    return out


def estimate_scale(g, rec):
    """No mm_per_px: over tip sizes 4-80 px, the one whose blobs' nearest-
    neighbour spacing agrees with the recipe's pitch/tip ratio."""
    best = None
    px_, py_ = rec["pitch_mm"]
    for t in np.geomspace(4, 80, 16):
        b = blobs_at(g, t)
        b = [q for q in b if 0.3 * t * t <= q[2] <= 2.5 * t * t]
        if len(b) < 2:
            continue
        pts = np.array([(q[0], q[1]) for q in b])
        d = np.hypot(pts[:, None, 0] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1])
        np.fill_diagonal(d, np.inf)
        nn = np.median(d.min(axis=1))
        pitch = min(px_, py_) if rec["rows"] > 1 else px_
        implied = rec["pin_mm"] / pitch * nn
        if not (t / 1.6 < implied < t * 1.6):
            continue
        score = len(b)
        if best is None or score > best[0]:
            best = (score, pitch / nn)
    if best is None:
        raise ValueError("scale not found")
    return best[1]


def nominal(rec):
    px_, py_ = rec["pitch_mm"]
    rows, cols = rec["rows"], rec["cols"]
    skip = {tuple(s) for s in rec.get("skip", [])}
    return [(i, j, (j - (cols - 1) / 2) * px_, (i - (rows - 1) / 2) * py_)
            for i in range(rows) for j in range(cols) if (i, j) not in skip]


def fit_similarity(src, dst, scale=None):
    """dst = t + s R src (least squares; s fixed when given)."""
    src, dst = np.asarray(src, float), np.asarray(dst, float)
    ms, md = src.mean(0), dst.mean(0)
    a, b = src - ms, dst - md
    sxx = (a * a).sum()
    c = (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]).sum()
    s_ = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum()
    th = math.atan2(s_, c)
    s = scale if scale else math.hypot(c, s_) / max(sxx, 1e-12)
    R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    t = md - s * (R @ ms)
    return s, th, t


def top(g, rec):
    if rec["polarity"] == "dark":
        g = 1.0 - g
    mmpp = rec.get("mm_per_px") or estimate_scale(g, rec)
    tip = rec["pin_mm"] / mmpp
    tip_area = tip * tip if rec["pin_shape"] == "square" else math.pi * tip * tip / 4
    blobs = blobs_at(g, tip)
    pts = np.array([(b[0], b[1]) for b in blobs]) if blobs else np.zeros((0, 2))
    areas = np.array([b[2] for b in blobs])
    pin_like = [k for k in range(len(blobs)) if 0.3 * tip_area <= areas[k] <= 3 * tip_area]
    if len(pin_like) < 1:
        raise ValueError("no pins")
    px_, py_ = rec["pitch_mm"]
    s = 1.0 / mmpp
    P, Q = px_ * s, py_ * s
    rng = np.random.default_rng(0)
    best = (0, None)
    cand = pts[pin_like]
    # RANSAC: a blob as a node, a neighbour at one x pitch gives the rotation.
    for _ in range(300):
        a = cand[rng.integers(len(cand))]
        d = np.hypot(*(cand - a).T)
        nb = np.nonzero((d > 0.8 * P) & (d < 1.2 * P))[0]
        if len(nb) == 0:
            th = 0.0
        else:
            v = cand[nb[rng.integers(len(nb))]] - a
            th = math.atan2(v[1], v[0])
            th = (th + math.pi / 4) % (math.pi / 2) - math.pi / 4 if rec["rows"] > 1 and px_ == py_ else th
            if abs(th) > math.radians(12):
                th = (th + math.pi) % (2 * math.pi) - math.pi
                if abs(th) > math.radians(12):
                    continue
        c, sn = math.cos(th), math.sin(th)
        rel = cand - a
        gu = (c * rel[:, 0] + sn * rel[:, 1]) / P
        gv = (-sn * rel[:, 0] + c * rel[:, 1]) / Q
        res = np.hypot((gu - np.round(gu)) * P, (gv - np.round(gv)) * Q)
        n_in = int((res < 0.2 * min(P, Q)).sum())
        if n_in > best[0]:
            best = (n_in, (a, th))
    a, th = best[1]
    c, sn = math.cos(th), math.sin(th)
    rel = cand - a
    gu = (c * rel[:, 0] + sn * rel[:, 1]) / P
    gv = (-sn * rel[:, 0] + c * rel[:, 1]) / Q
    ok = np.hypot((gu - np.round(gu)) * P, (gv - np.round(gv)) * Q) < 0.2 * min(P, Q)
    iu, iv = np.round(gu[ok]).astype(int), np.round(gv[ok]).astype(int)
    # Window: the rows x cols placement holding the most lattice points.
    nom = nominal(rec)
    # occupancy histogram and a summed-area table over window placements
    rows, cols = rec["rows"], rec["cols"]
    ou, ov = iu.min() - cols, iv.min() - rows
    occ = np.zeros((iv.max() - ov + rows + 1, iu.max() - ou + cols + 1), np.int64)
    occ[iv - ov, iu - ou] = 1
    sat = np.pad(occ.cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    cnt = sat[rows:, cols:] - sat[:-rows, cols:] - sat[rows:, :-cols] + sat[:-rows, :-cols]
    a0, b0 = np.unravel_index(int(np.argmax(cnt)), cnt.shape)
    i0, j0 = int(a0 + ov), int(b0 + ou)
    src, dst = [], []
    for k, (uu, vv) in zip(np.nonzero(ok)[0], zip(iu, iv)):
        i, j = vv - i0, uu - j0
        if 0 <= i < rec["rows"] and 0 <= j < rec["cols"]:
            src.append(((j - (rec["cols"] - 1) / 2) * px_, (i - (rec["rows"] - 1) / 2) * py_))
            dst.append(cand[k])
    known = rec.get("mm_per_px")
    s_fit, th, t = fit_similarity(src, dst, s if known else None)
    # one round of outlier rejection (bent pins)
    R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    pred = (s_fit * (R @ np.array(src).T)).T + t
    r = np.hypot(*(pred - np.array(dst)).T)
    keep = r <= max(3 * np.median(r), 1.0)
    if keep.sum() >= 2:
        s_fit, th, t = fit_similarity(np.array(src)[keep], np.array(dst)[keep], s if known else None)
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    mmpp = 1.0 / s_fit
    tol_px = rec["tolerance"]["position_mm"] / mmpp
    tip_area = (rec["pin_mm"] / mmpp) ** 2 * (1 if rec["pin_shape"] == "square" else math.pi / 4)
    used = set()
    pins = []
    matched_areas = []
    for (i, j, u, v) in nom:
        x, y = s_fit * (R @ np.array([u, v])) + t
        d = np.hypot(pts[:, 0] - x, pts[:, 1] - y) if len(pts) else np.array([])
        k = int(np.argmin(d)) if len(d) else -1
        if k < 0 or d[k] > 0.4 * min(P, Q) * s_fit / s or k in used:
            pins.append(dict(row=i, col=j, status="missing", x_px=None, y_px=None, nx=x, ny=y))
            continue
        used.add(k)
        matched_areas.append(areas[k])
        pins.append(dict(row=i, col=j, k=k, x_px=float(pts[k, 0]), y_px=float(pts[k, 1]), dist=float(d[k]), nx=x, ny=y))
    ref_area = float(np.median(matched_areas)) if matched_areas else tip_area
    lo, hi = rec["tolerance"].get("tip_area", [0.6, 1.5])
    for p in pins:
        if "k" not in p:
            continue
        ar = areas[p["k"]] / ref_area
        p["area_ratio"] = float(ar)
        p["status"] = "damaged" if not lo <= ar <= hi else ("bent" if p["dist"] > tol_px else "ok")
    # Extras: unassigned blobs of >= 1/4 tip near the grid.
    us = [q[2] for q in nom]
    vs = [q[3] for q in nom]
    extras = []
    Rt = R.T
    for k in range(len(pts)):
        if k in used or areas[k] < 0.25 * ref_area:
            continue
        uu, vv = (Rt @ (pts[k] - t)) / s_fit
        if min(us) - 1.5 * px_ <= uu <= max(us) + 1.5 * px_ and min(vs) - 1.5 * py_ <= vv <= max(vs) + 1.5 * py_:
            extras.append(dict(x_px=float(pts[k, 0]), y_px=float(pts[k, 1]), area_ratio=float(areas[k] / ref_area)))
    return pins, extras


def side(g, rec):
    s = 1.0 - g  # silhouette bright
    s8 = np.clip(s * 255, 0, 255).astype(np.uint8)
    _, bw = cv2.threshold(s8, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    bw = cv2.morphologyEx(bw, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    H, W = bw.shape
    # column tops of the lowest long run: housing edge candidates
    tops = []
    for x in range(0, W, 2):
        col = bw[:, x] > 0
        if not col.any():
            continue
        # longest run
        d = np.diff(np.concatenate([[0], col.astype(int), [0]]))
        st, en = np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]
        k = int(np.argmax(en - st))
        if en[k] - st[k] > 5:
            tops.append((x, st[k]))
    if len(tops) < 6:
        raise ValueError("no housing")
    tops = np.array(tops, float)
    rng = np.random.default_rng(0)
    best = (0, None)
    for _ in range(300):
        a, b = tops[rng.choice(len(tops), 2, replace=False)]
        if a[0] == b[0]:
            continue
        m = (b[1] - a[1]) / (b[0] - a[0])
        r = tops[:, 1] - (a[1] + m * (tops[:, 0] - a[0]))
        n = int((np.abs(r) < 2).sum())
        if n > best[0]:
            best = (n, (a, m))
    a, m = best[1]
    r = tops[:, 1] - (a[1] + m * (tops[:, 0] - a[0]))
    inl = tops[np.abs(r) < 2]
    m, c0 = np.polyfit(inl[:, 0], inl[:, 1], 1)
    norm = math.hypot(1, m)
    # components above the edge
    ys, xs = np.mgrid[0:H, 0:W]
    above = (bw > 0) & (ys < (m * xs + c0) - 2)
    n, lab, st, cen = cv2.connectedComponentsWithStats(above.astype(np.uint8), connectivity=8)
    mmpp = rec.get("mm_per_px")
    bars, dust = [], []
    for i in range(1, n):
        x0, y0, w, h, area = st[i]
        bottom_gap = (m * (x0 + w / 2) + c0) - (y0 + h)
        if h >= 2 * w and bottom_gap < 4:
            bars.append(i)
        elif area >= 4:
            dust.append(i)
    if not bars:
        raise ValueError("no pins")
    # tip: half-level crossing along the bar's column from above
    back = float(np.median(g[~(bw > 0)])) if (~(bw > 0)).any() else 1.0
    silv = float(np.median(g[bw > 0]))
    half = 0.5 * (back + silv)
    found = []
    for i in bars:
        x0, y0, w, h, area = st[i]
        mask = lab[y0:y0 + h, x0:x0 + w] == i
        cx = float(x0 + (mask * np.arange(w)[None, :]).sum() / mask.sum())
        xi = int(round(cx))
        prof = g[:, max(0, min(W - 1, xi))]
        yt = y0
        yy = None
        for y in range(max(1, yt - 6), min(H - 1, yt + 6)):
            if prof[y - 1] >= half > prof[y]:
                yy = y - 1 + (prof[y - 1] - half) / (prof[y - 1] - prof[y])
                break
        if yy is None:
            yy = float(yt)
        hpx = ((m * cx + c0) - yy) / norm
        ualong = (cx + m * yy) / norm
        found.append((ualong, cx, yy, hpx, float(area)))
    found.sort()
    px_ = rec["pitch_mm"][0]
    if mmpp is None:
        if len(found) < 2:
            mmpp = rec["pin_mm"] / float(np.median([st[i][2] for i in bars]))
        else:
            sp = np.diff([f[0] for f in found])
            p1 = float(np.median(sp))
            k = np.maximum(np.round(sp / p1), 1)
            mmpp = px_ / float(np.median(sp / k))
    P = px_ / mmpp
    cols = rec["cols"]
    ua = np.array([f[0] for f in found])
    best = None
    for off in ua:
        for j0 in range(cols):
            start = off - j0 * P
            idx = np.round((ua - start) / P)
            inwin = (np.abs(ua - start - idx * P) < 0.3 * P) & (idx >= 0) & (idx < cols)
            cnt = int(inwin.sum())
            if best is None or cnt > best[0]:
                best = (cnt, start)
    start = best[1]
    # refine the offset on the members
    idx = np.round((ua - start) / P)
    memb = (np.abs(ua - start - idx * P) < 0.3 * P) & (idx >= 0) & (idx < cols)
    if memb.any():
        start = float(np.median(ua[memb] - idx[memb] * P))
    tol = rec["tolerance"]
    pins, used = [], set()
    for j in range(cols):
        un = start + j * P
        d = np.abs(ua - un)
        k = int(np.argmin(d))
        if d[k] > 0.4 * P or k in used:
            pins.append(dict(row=0, col=j, status="missing", x_px=None, y_px=None))
            continue
        used.add(k)
        f = found[k]
        hmm = f[3] * mmpp
        if d[k] * mmpp > tol["position_mm"]:
            stt = "bent"
        elif hmm < tol["height_mm"] - tol["height_tol_mm"]:
            stt = "short"
        elif hmm > tol["height_mm"] + tol["height_tol_mm"]:
            stt = "high"
        else:
            stt = "ok"
        pins.append(dict(row=0, col=j, status=stt, x_px=f[1], y_px=f[2], height_mm=hmm))
    extras = []
    for k, f in enumerate(found):
        if k not in used:
            extras.append(dict(x_px=f[1], y_px=f[2], area_ratio=None))
    tip_area = (rec["pin_mm"] / mmpp) ** 2
    for i in dust:
        if st[i][4] >= 0.25 * tip_area:
            extras.append(dict(x_px=float(cen[i][0]), y_px=float(cen[i][1]), area_ratio=float(st[i][4] / tip_area)))
    return pins, extras


def inspect(image, recipe_path):
    with open(recipe_path, "rb") as fh:
        rec = tomllib.load(fh)
    g = load_gray(image)
    pins, extras = (top if rec["view"] == "top" else side)(g, rec)
    verdict = "pass" if all(p["status"] == "ok" for p in pins) and not extras else "fail"
    return dict(verdict=verdict, pins=pins, extras=extras)


if __name__ == "__main__":
    try:
        print(json.dumps(inspect(sys.argv[1], sys.argv[2])))
    except Exception as e:  # one image's failure is its error, as in pinsight
        print(json.dumps(dict(error=str(e))))
