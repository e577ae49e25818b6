"""Reads a Q-DAS ASCII transfer file (.dfq) with an independent reader, the
PyPI package `aqdefreader` (successfactory), and prints what it found as
JSON: per part its number and per characteristic its K2xxx fields and
measured values with date/time and batch.

    python3 tests/python/read_dfq.py FILE.dfq
"""
import contextlib
import json
import sys

from aqdefreader import read_dfq_file


def num(v):
    # aqdefreader turns only unsigned, comma-decimal numbers into numbers;
    # a point-decimal or negative value stays text.
    try:
        return float(v)
    except (TypeError, ValueError):
        return v


def main():
    # The reader prints what it detects (encoding, counts) to stdout.
    with contextlib.redirect_stdout(sys.stderr):
        f = read_dfq_file(sys.argv[1])
    parts = []
    for p in f.get_parts():
        chars = []
        for c in p.get_characteristics():
            chars.append(
                {
                    "fields": {k: str(c.get_data(k)) for k in c.get_data_keys()},
                    "values": [num(m.value) for m in c.get_measurements()],
                    "dates": [
                        m.datetime.isoformat() if m.datetime else None
                        for m in c.get_measurements()
                    ],
                }
            )
        parts.append({"part": str(p.get_part_no()), "characteristics": chars})
    json.dump({"parts": parts}, sys.stdout)


if __name__ == "__main__":
    main()
