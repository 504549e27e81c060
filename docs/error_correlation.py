#!/usr/bin/env python3
"""Correlation of the extractor's signed angle errors within each photo (journal, session 20).

Usage: docs/error_correlation.py SETDIR TABLE.csv [SETDIR TABLE.csv ...]

For every pair of angles measured on the same `ok` row, prints the correlation and slope of their
signed errors (reading minus truth.csv; rows beyond 6 MAD of either dropped), and how much of
psi's and theta1's stated sigmas the shared part `frame_err_deg` is. Pure standard library.
"""
import csv
import math
import statistics
import sys

ANGLES = ["psi", "delta1", "delta2", "theta1", "theta2"]


def signed(a, b):
    return (a - b + 180.0) % 360.0 - 180.0


def rows(setdir, table):
    truth = {r["file"]: r for r in csv.DictReader(open(f"{setdir}/truth.csv"))}
    for r in csv.DictReader(open(table)):
        if r["status"] != "ok":
            continue
        t = truth[r["file"]]
        d = {}
        for a in ANGLES:
            if r.get(a + "_deg") and t.get(a + "_deg"):
                d[a] = (signed(float(r[a + "_deg"]), float(t[a + "_deg"])), float(r[a + "_err_deg"]))
        if r.get("frame_err_deg"):
            d["frame"] = float(r["frame_err_deg"])
        yield d


def pair(data, a, b):
    p = [(d[a][0], d[b][0]) for d in data if a in d and b in d]
    if len(p) < 5:
        return None
    mx, my = statistics.median(x for x, _ in p), statistics.median(y for _, y in p)
    sx = statistics.median(abs(x - mx) for x, _ in p) or 1e-12
    sy = statistics.median(abs(y - my) for _, y in p) or 1e-12
    p = [(x, y) for x, y in p if abs(x - mx) < 6 * sx and abs(y - my) < 6 * sy]
    mx, my = statistics.mean(x for x, _ in p), statistics.mean(y for _, y in p)
    sxy = sum((x - mx) * (y - my) for x, y in p)
    sxx = sum((x - mx) ** 2 for x, _ in p)
    syy = sum((y - my) ** 2 for _, y in p)
    return len(p), sxy / math.sqrt(sxx * syy), sxy / sxx


def main(argv):
    if len(argv) < 2 or len(argv) % 2:
        sys.exit(__doc__)
    data = []
    for i in range(0, len(argv), 2):
        data.extend(rows(argv[i], argv[i + 1]))
    for a, b in [("psi", "theta1"), ("psi", "theta2"), ("psi", "delta1"), ("psi", "delta2"), ("theta1", "theta2")]:
        r = pair(data, a, b)
        if r:
            print(f"{a:6s} {b:6s}  n {r[0]:4d}  correlation {r[1]:+.2f}  slope {r[2]:+.2f}")
    for a in ["psi", "theta1"]:
        f = [d["frame"] / d[a][1] for d in data if "frame" in d and a in d]
        if f:
            print(f"frame_err_deg / {a}_err_deg: median {statistics.median(f):.2f}, max {max(f):.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
