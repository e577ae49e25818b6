#!/usr/bin/env python3
"""Independent readers of pinsight's Parquet outputs (issue 19).

pyarrow (the Arrow project's own reader) reads every table and its schema;
DuckDB queries the shards' hive-partitioned data sets with SQL. Each figure
is compared with what pinsight itself reports in yield.json / monitor.json.

  check_parquet.py yield WHOLE_DIR SHARDS_GLOB
      WHOLE_DIR: a single run's --out with --items json,csv,parquet
      SHARDS_GLOB: the shards' --out folders (their tables partitioned,
      e.g. by part,lot), as a glob: 'tmp/shard-*'
  check_parquet.py monitor DIR
      DIR: a monitor --out with --items parquet

Prints one line per check; exits 1 on the first mismatch.
"""

import json
import math
import sys

import duckdb
import pyarrow as pa
import pyarrow.parquet as pq

Z95 = 1.959963984540054


def fail(msg):
    print("MISMATCH: " + msg)
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)
    print("ok: " + msg)


IMAGES = {
    "item": pa.uint64(), "name": pa.string(), "verdict": pa.string(),
    "part": pa.string(), "lot": pa.string(), "rig": pa.string(),
    "motor_rpm": pa.float64(), "clearance_mm": pa.float64(),
    "cycle": pa.uint64(), "log": pa.string(),
    "log_time": pa.timestamp("ns", tz="UTC"), "view": pa.string(),
    "pins": pa.uint32(), "ok": pa.uint32(), "missing": pa.uint32(),
    "damaged": pa.uint32(), "bent": pa.uint32(), "short": pa.uint32(),
    "high": pa.uint32(), "extras": pa.uint32(), "mm_per_px": pa.float64(),
    "rotation_deg": pa.float64(), "fit_rms_px": pa.float64(),
    "error_kind": pa.string(), "error": pa.string(),
}
PINS = {
    "item": pa.uint64(), "part": pa.string(), "lot": pa.string(),
    "rig": pa.string(), "row": pa.uint32(), "col": pa.uint32(),
    "status": pa.string(), "x_px": pa.float32(), "y_px": pa.float32(),
    "dx_mm": pa.float32(), "dy_mm": pa.float32(),
    "offset_mm": pa.float32(), "area_ratio": pa.float32(),
    "height_mm": pa.float32(),
}


def wilson(k, n):
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    z2 = Z95 * Z95
    d = 1 + z2 / n
    c = (p + z2 / (2 * n)) / d
    h = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / d
    return (max(c - h, 0.0), min(c + h, 1.0))


def schema_is(table, want, what):
    got = {f.name: f.type for f in table.schema}
    check(got == want, f"{what}: pyarrow reads the documented schema")


def yield_check(whole, shards_glob):
    y = json.load(open(f"{whole}/yield.json"))
    rep, items = y["report"], y["items"]
    img = pq.read_table(f"{whole}/images.parquet")
    pins = pq.read_table(f"{whole}/pins.parquet")
    schema_is(img, IMAGES, "images.parquet")
    schema_is(pins, PINS, "pins.parquet")
    check(img.num_rows == len(items), f"images: {img.num_rows} rows = the items of yield.json")
    # Nanosecond times as integers (datetime has microseconds only).
    lt = img.column("log_time").cast(pa.int64())
    rows = img.drop_columns(["log_time"]).to_pylist()
    for i, (r, it) in enumerate(zip(rows, items)):
        meta = it["meta"]
        ins = it.get("inspection")
        same = (
            r["item"] == i and r["name"] == it["name"] and r["verdict"] == it["status"]
            and r["lot"] == meta["lot"] and r["rig"] == meta["rig_id"]
            and r["motor_rpm"] == meta["motor_rpm"] and r["cycle"] == meta["cycle"]
            and r["log"] == meta["log"]
            and r["part"] == (meta["part_number"] or (ins or {}).get("part_number"))
            and r["pins"] == (len(ins["pins"]) if ins else None)
            and r["ok"] == (ins["counts"]["ok"] if ins else None)
            and r["mm_per_px"] == (ins["grid"]["mm_per_px"] if ins else None)
            and r["error"] == ((it.get("error") or {}).get("message"))
        )
        if not same:
            fail(f"images row {i} differs from yield.json's item: {r} / {it['name']}")
    print("ok: every images row is its yield.json item")
    stamped = [v for v in lt.to_pylist() if v is not None]
    from_logs = sum(1 for it in items if it["meta"]["log"] and "#" in it["name"])
    check(all(1e18 < v < 4e18 for v in stamped) and len(stamped) == from_logs,
          f"log_time: {len(stamped)} images from rig logs stamped with their log time")
    want_pins = [(i, p) for i, it in enumerate(items) if it.get("inspection")
                 for p in it["inspection"]["pins"]]
    check(pins.num_rows == len(want_pins) == rep["pins_inspected"],
          f"pins: {pins.num_rows} rows = the pins of yield.json = pins_inspected")
    f32 = lambda v: None if v is None else float(pa.scalar(v, pa.float32()).as_py())
    for r, (i, p) in zip(pins.to_pylist(), want_pins):
        same = (r["item"] == i and r["row"] == p["row"] and r["col"] == p["col"]
                and r["status"] == p["status"]
                and all(r[k] == f32(p[k]) for k in
                        ["x_px", "y_px", "dx_mm", "dy_mm", "offset_mm", "area_ratio", "height_mm"]))
        if not same:
            fail(f"pins row differs from yield.json: {r} / {p}")
    print("ok: every pins row is its yield.json pin (as 32-bit floats)")

    # DuckDB over the shards' partitioned data sets.
    con = duckdb.connect()
    src = (f"read_parquet('{shards_glob}/images/**/*.parquet', hive_partitioning = true, "
           f"hive_types = {{'part': VARCHAR, 'lot': VARCHAR}})")
    got = con.execute(f"""
        SELECT coalesce(lot, '(no lot)') AS lot,
               count(*) FILTER (WHERE verdict IN ('pass', 'fail')) AS inspected,
               count(*) FILTER (WHERE verdict = 'pass') AS passed,
               count(*) FILTER (WHERE verdict = 'error') AS errors
        FROM {src} GROUP BY 1 ORDER BY 1""").fetchall()
    assert rep["group_by"] == "lot", rep["group_by"]
    want = sorted((g["key"], g["inspected"], g["passed"], g["errors"]) for g in rep["groups"])
    check(got == want, f"DuckDB yield by lot over the shards' partitions = pinsight's groups {want}")
    for g in rep["groups"]:
        lo, hi = wilson(g["passed"], g["inspected"])
        if abs(lo - g["ci95"][0]) > 1e-12 or abs(hi - g["ci95"][1]) > 1e-12:
            fail(f"Wilson interval of {g['key']}: {g['ci95']} against {(lo, hi)}")
    print("ok: every group's Wilson interval recomputed from DuckDB's counts")
    n, passed, errors = con.execute(
        f"SELECT count(*), count(*) FILTER (WHERE verdict = 'pass'), "
        f"count(*) FILTER (WHERE verdict = 'error') FROM {src}").fetchone()
    check((n, passed, errors) == (rep["items"], rep["passed"], rep["errors"]),
          f"DuckDB totals {n} items, {passed} passed, {errors} errors = the report's")
    psrc = (f"read_parquet('{shards_glob}/pins/**/*.parquet', hive_partitioning = true, "
            f"hive_types = {{'part': VARCHAR, 'lot': VARCHAR}})")
    pins_n, bad = con.execute(
        f"SELECT count(*), count(*) FILTER (WHERE status <> 'ok') FROM {psrc}").fetchone()
    check((pins_n, bad) == (rep["pins_inspected"], rep["defective_pins"]),
          f"DuckDB pins {pins_n}, defective {bad} = the report's")
    dppm = bad / pins_n * 1e6
    check(abs(dppm - rep["dppm"]) <= 1e-9 * dppm, f"DPPM {dppm:.3f} = the report's")
    pareto = dict(con.execute(
        f"SELECT status, count(*) FROM {psrc} WHERE status <> 'ok' GROUP BY 1").fetchall())
    extras = con.execute(f"SELECT coalesce(sum(extras), 0) FROM {src}").fetchone()[0]
    if extras:
        pareto["extra"] = extras
    want = {p["kind"]: p["count"] for p in rep["pareto"]}
    check(pareto == want, f"DuckDB Pareto {pareto} = the report's")
    # The worst position's mean offset (32-bit floats summed in double).
    w = rep["worst_pins"][0]
    m = con.execute(
        f"SELECT avg(offset_mm::DOUBLE), count(*) FROM {psrc} WHERE part = ? AND \"row\" = ? "
        f"AND col = ?", [w["part_number"], w["row"], w["col"]]).fetchone()
    check(m[1] == w["inspected"], f"DuckDB pins at r{w['row']}c{w['col']}: {m[1]} = inspected")
    if w["mean_offset_mm"] is not None:
        check(abs(m[0] - w["mean_offset_mm"]) < 1e-6,
              f"mean offset at r{w['row']}c{w['col']} {m[0]:.7f} ≈ {w['mean_offset_mm']:.7f} mm")


def monitor_check(d):
    run = json.load(open(f"{d}/monitor.json"))
    t = pq.read_table(f"{d}/cycles.parquet")
    fixed = {
        "log": pa.string(), "lot": pa.string(), "part": pa.string(),
        "cycle": pa.uint64(), "t_start": pa.timestamp("ns", tz="UTC"),
        "motor_rpm": pa.float64(), "status": pa.string(), "reasons": pa.string(),
        "failed_objects": pa.uint32(), "worst_by": pa.float64(),
    }
    got = {f.name: f.type for f in t.schema}
    check(all(got.get(k) == v for k, v in fixed.items()), "cycles.parquet: the documented columns")
    values = [c["name"] for c in run["spc"]]
    check(all(got.get("value_" + "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in n))
              == pa.float64() for n in values), f"cycles.parquet: a value column per {values}")
    cycles = [(l["file"], c) for l in run["logs"] if "Ok" in l["report"]
              for c in l["report"]["Ok"]["cycles"]]
    check(t.num_rows == len(cycles), f"cycles: {t.num_rows} rows = the cycles of monitor.json")
    starts = t.column("t_start").cast(pa.int64()).to_pylist()
    rows = t.drop_columns(["t_start"]).to_pylist()
    check(starts == [c["t_start_ns"] for _, c in cycles], "t_start = each cycle's t_start_ns")
    for r, (f, c) in zip(rows, cycles):
        if (r["log"], r["cycle"], r["status"], r["motor_rpm"]) != (f, c["index"], c["status"], c["motor_rpm"]):
            fail(f"cycles row {r} differs from monitor.json's cycle {c['index']} of {f}")
        for n in values:
            col = "value_" + "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in n)
            if r[col] != c["values"].get(n):
                fail(f"value {n} of cycle {c['index']}: {r[col]} / {c['values'].get(n)}")
    print("ok: every cycles row is its monitor.json cycle, values included")
    con = duckdb.connect()
    counts = dict(con.execute(
        f"SELECT status, count(*) FROM read_parquet('{d}/cycles.parquet') GROUP BY 1").fetchall())
    check((counts.get("ok", 0), counts.get("nok", 0), counts.get("not_evaluated", 0))
          == (run["ok"], run["nok"], run["not_evaluated"]),
          f"DuckDB verdict counts {counts} = monitor.json's")


if __name__ == "__main__":
    if sys.argv[1] == "yield":
        yield_check(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "monitor":
        monitor_check(sys.argv[2])
    else:
        sys.exit(__doc__)
