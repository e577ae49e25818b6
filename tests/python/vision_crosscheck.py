#!/usr/bin/env python3
"""Scores pinsight and the plain OpenCV baseline on a folder rendered by
connector_render.py, against its truth, overall and per factor.

    python3 tests/python/vision_crosscheck.py DIR [--pinsight BIN] [--jobs N]
        [--only pinsight|baseline] [--list] [--csv FILE]

pinsight is run as a user runs it (`pinsight inspect -r RECIPE IMAGE --json`).
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import opencv_baseline  # noqa: E402


def run_pinsight(binary, img, rec):
    p = subprocess.run([binary, "inspect", "-r", rec, img, "--json"], capture_output=True, text=True)
    try:
        item = json.loads(p.stdout)[0]
    except Exception:
        return dict(error=f"no JSON (exit {p.returncode}): {p.stderr.strip()[:200]}")
    if item.get("inspection") is None:
        return dict(error=item.get("error") or item.get("status"))
    ins = item["inspection"]
    return dict(verdict=ins["verdict"], pins=ins["pins"], extras=ins["extras"])


def score(truth, res):
    o = dict(error=res.get("error"), verdict_ok=False, pins=len(truth["pins"]), pins_wrong=len(truth["pins"]),
             ok_err=[], what=[])
    if o["error"]:
        o["what"].append("error: " + str(o["error"])[:120])
        return o
    o["verdict_ok"] = res["verdict"] == truth["verdict"]
    got = {(p["row"], p["col"]): p for p in res["pins"]}
    wrong = 0
    for t in truth["pins"]:
        g = got.get((t["row"], t["col"]))
        st = g["status"] if g else "absent"
        if st != t["defect"]:
            wrong += 1
            o["what"].append(f"({t['row']},{t['col']}) {t['defect']}->{st}")
        if t["defect"] == "ok" and g and g.get("x_px") is not None:
            o["ok_err"].append(math.hypot(g["x_px"] - t["x_px"], g["y_px"] - t["y_px"]))
    o["pins_wrong"] = wrong
    # extras: matched within max(8 px, 0.5 tip)
    tipr = max(8.0, 0.5 * truth["factors"]["tip_px"])
    te, ge = truth["extras"], res["extras"]
    used = set()
    for e in te:
        hit = [k for k, g in enumerate(ge) if k not in used and math.hypot(g["x_px"] - e["x_px"], g["y_px"] - e["y_px"]) < tipr]
        if hit:
            used.add(hit[0])
        else:
            o["what"].append(f"missed extra a{e.get('area_ratio')}")
    for k, g in enumerate(ge):
        if k not in used:
            o["what"].append(f"spurious extra ({g['x_px']:.0f},{g['y_px']:.0f}) a{(g.get('area_ratio') or 0):.2f}")
    return o


def one(args):
    jpath, binary, which = args
    d = os.path.dirname(jpath)
    truth = json.load(open(jpath))
    img, rec = os.path.join(d, truth["image"]), os.path.join(d, truth["recipe"])
    out = dict(seed=truth["factors"]["seed"], f=truth["factors"])
    if which in ("both", "pinsight"):
        out["pinsight"] = score(truth, run_pinsight(binary, img, rec))
    if which in ("both", "baseline"):
        try:
            res = opencv_baseline.inspect(img, rec)
        except Exception as e:
            res = dict(error=str(e))
        out["baseline"] = score(truth, res)
    return out


NUMERIC = [("mm_per_px", 0.008, 0.05), ("megapixels", 0.0768, 5.0), ("aspect", 1, 3), ("tip_px", 4, 60),
           ("contrast", 0.3, 1.0), ("noise_dn", 0, 16), ("blur_px", 0, 2.5), ("vignetting", 0, 0.5),
           ("gradient", 0, 0.2), ("gain", 0.6, 1.3), ("texture_dn", 0.5, 6)]
CATS = ["view", "polarity", "pin_shape", "rows", "psf", "scale_in_recipe", "bits", "colour", "jpeg"]


def cat(f, k):
    if k == "jpeg":
        q = f["jpeg_quality"]
        return "lossless" if q is None else ("q50-74" if q < 75 else "q75-100")
    if k == "rows":
        return str(min(f["rows"], 4))
    return str(f[k])


def line(label, sel, who):
    n = len(sel)
    if n == 0:
        return
    s = [x[who] for x in sel]
    right = sum(x["verdict_ok"] for x in s)
    err = sum(1 for x in s if x["error"])
    pins = sum(x["pins"] for x in s)
    pw = sum(x["pins_wrong"] for x in s)
    e = [v for x in s for v in x["ok_err"]]
    rms = math.sqrt(sum(v * v for v in e) / len(e)) if e else float("nan")
    print(f"  {label:30} {n:5} {100 * right / n:7.2f} % {err:4} {100 * (pins - pw) / max(pins, 1):7.2f} % {rms:7.3f}")


def report(res, who, listing):
    n = len(res)
    s = [x[who] for x in res]
    right = sum(x["verdict_ok"] for x in s)
    err = sum(1 for x in s if x["error"])
    pins = sum(x["pins"] for x in s)
    pw = sum(x["pins_wrong"] for x in s)
    e = sorted(v for x in s for v in x["ok_err"])
    rms = math.sqrt(sum(v * v for v in e) / len(e)) if e else float("nan")
    med = e[len(e) // 2] if e else float("nan")
    p99 = e[int(len(e) * 0.99)] if e else float("nan")
    print(f"\n== {who}: {n} images: connector verdicts right {right}/{n} = {100 * right / n:.2f} %; errors {err}; "
          f"pin statuses right {pins - pw}/{pins} = {100 * (pins - pw) / pins:.2f} %; ok-pin centre RMS {rms:.3f} px "
          f"(median {med:.3f}, p99 {p99:.3f}) over {len(e)} pins")
    print("  per factor: bin, images, verdicts right, errors, pin statuses right, ok-pin RMS px")
    for k, lo, hi in NUMERIC:
        for b in range(4):
            a0, a1 = lo + (hi - lo) * b / 4, lo + (hi - lo) * (b + 1) / 4
            sel = [x for x in res if a0 <= x["f"][k] < a1 or (b == 3 and x["f"][k] >= a1) or (b == 0 and x["f"][k] < a0)]
            line(f"{k} {a0:.3g}-{a1:.3g}", sel, who)
    for k in CATS:
        for v in sorted({cat(x["f"], k) for x in res}):
            line(f"{k}: {v}", [x for x in res if cat(x["f"], k) == v], who)
    for kind in ["good part", "missing", "bent", "damaged", "extra", "short", "high"]:
        sel = [x for x in res if (not x["f"]["defects"]) if kind == "good part"] if kind == "good part" else \
            [x for x in res if kind in x["f"]["defects"]]
        line(f"defects: {kind}", sel, who)
    if listing:
        for x in res:
            o = x[who]
            if not o["verdict_ok"] or o["pins_wrong"]:
                f = x["f"]
                print(f"  seed {x['seed']} {f['view']} {f['polarity']} {f['pin_shape']} {f['rows']}x{f['cols']} "
                      f"{f['width']}x{f['height']} {f['mm_per_px']:.4f}{'' if f['scale_in_recipe'] else ' est'} "
                      f"tip {f['tip_px']:.1f} c {f['contrast']:.2f} n {f['noise_dn']:.1f} b {f['blur_px']:.2f} "
                      f"{f['psf']} vig {f['vignetting']:.2f} gain {f['gain']:.2f} {f['bits']}b "
                      f"{'colour ' if f['colour'] else ''}q{f['jpeg_quality']} {f['defects']}: "
                      f"{'RIGHT ' if o['verdict_ok'] else ''}{'; '.join(o['what'])}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--pinsight", default="target/release/pinsight")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", default="both")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--json", help="write the per-image scores here")
    a = ap.parse_args()
    js = sorted(glob.glob(os.path.join(a.dir, "py-*.json")))
    with ProcessPoolExecutor(a.jobs) as ex:
        res = list(ex.map(one, [(j, a.pinsight, a.only) for j in js], chunksize=4))
    for who in ("pinsight", "baseline"):
        if who in res[0]:
            report(res, who, a.list)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh)


if __name__ == "__main__":
    main()
