#!/usr/bin/env python3
"""Extraction accuracy against ground truth, as quoted in the README.

Usage: compare_truth.py DIR TABLE.csv [DIR TABLE.csv ...]
DIR holds a synthetic set (`streakfit synth`, with truth.csv); TABLE.csv is `streakfit extract
DIR --out TABLE.csv`. Prints, per angle, the median and 90th percentile of |measured - true| over
the `ok` rows where both are defined, how many rows were `ok`, the sigma ratio
median(|error| / stated sigma) / 0.6745 (1 for honest Gaussian 1-sigma errors), and the `ok`
rows misread: an angle more than 5 stated sigma and more than 1 degree off. Where truth.csv has
the angles as the camera shows them (`*_image_deg`, since session 15), "camera" is the median
|image - table| over the same rows: the part of the error a perfect measurement in the image
would still make without knowing the camera's tilt and distortion. "radius" is the median
signed error of the fitted ball radius in px. Where DIR also holds psi_bound.csv (`streakfit
bench psi-bound` with the synth flags of DIR, since session 25), "bound" compares psi with its
Cramér–Rao bound: the median |error| that a reader at the bound would have on every shot of
the set and on the `ok` rows, and the medians over the `ok` rows of |error| / bound and stated
sigma / bound (how many times the best possible sigma the extractor's errors and sigmas are).
A set of several materials also gets one line per material: the ball radius in the photo, `ok`
rows and the median |error| of psi, theta1, theta2 and delta1 (since session 36).
"""
import csv
import math
import statistics
import sys


def efficient_median(sigmas):
    """The m with mean_i P(|N(0, sigma_i^2)| <= m) = 1/2 (src/synth/bound.rs)."""
    lo, hi = 0.0, 10.0 * max(sigmas)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        share = sum(math.erf(mid / (s * math.sqrt(2.0))) for s in sigmas) / len(sigmas)
        lo, hi = (mid, hi) if share < 0.5 else (lo, mid)
    return 0.5 * (lo + hi)


def bound_line(folder, truth, ok):
    try:
        rows = list(csv.DictReader(open(f"{folder}/psi_bound.csv")))
    except FileNotFoundError:
        return None
    bound = {r["file"]: float(r["sigma_psi_bound_deg"]) for r in rows
             if r["sigma_psi_bound_deg"] and float(r.get("blind_r", "0") or 0) == 0.0}
    if not bound:
        return None
    ok_b = [r for r in ok if r["file"] in bound and r["psi_deg"] != ""]
    line = f"  bound   at the bound: all {len(bound)} shots {efficient_median(list(bound.values())):.4f}"
    if ok_b:
        errs = [angle_error(float(r["psi_deg"]), float(truth[r["file"]]["psi_deg"])) / bound[r["file"]]
                for r in ok_b]
        sds = [float(r["psi_err_deg"]) / bound[r["file"]] for r in ok_b if r["psi_err_deg"]]
        line += (f", the {len(ok_b)} ok rows {efficient_median([bound[r['file']] for r in ok_b]):.4f}"
                 f"; ok rows: |error|/bound {statistics.median(errs):.1f}")
        if sds:
            line += f", sigma/bound {statistics.median(sds):.1f}"
    return line


def angle_error(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def report(folder, table):
    truth = {r["file"]: r for r in csv.DictReader(open(f"{folder}/truth.csv"))}
    rows = list(csv.DictReader(open(table)))
    ok = [r for r in rows if r["status"] == "ok"]
    print(f"{folder}: {len(ok)}/{len(rows)} ok")
    for k in ["psi", "delta1", "delta2", "theta1", "theta2"]:
        errs, pulls, camera = [], [], []
        for r in ok:
            tv, mv = truth[r["file"]][f"{k}_deg"], r[f"{k}_deg"]
            if tv == "" or mv == "":
                continue
            e = angle_error(float(mv), float(tv))
            errs.append(e)
            iv = truth[r["file"]].get(f"{k}_image_deg", "")
            if iv != "":
                camera.append(angle_error(float(iv), float(tv)))
            if r[f"{k}_err_deg"]:
                pulls.append(e / float(r[f"{k}_err_deg"]))
        if not errs:
            print(f"  {k:7s} no measured values")
            continue
        errs.sort()
        p90 = errs[int(round(0.9 * (len(errs) - 1)))]
        ratio = statistics.median(pulls) / 0.6745 if pulls else float("nan")
        cam = f"  camera {statistics.median(camera):.3f}" if camera else ""
        print(f"  {k:7s} n {len(errs):3d}  median {statistics.median(errs):.3f}  p90 {p90:.3f}  sigma ratio {ratio:.2f}{cam}")
    # Signed error of the joint fit's ball radius: the impact point sits 2R from the disc's
    # centre, so a bias here moves P along the line of centres (journal, session 15).
    dr = [float(r["ball_radius_px"]) - float(truth[r["file"]]["ball_radius_px"])
          for r in ok if r.get("ball_radius_px")]
    if dr:
        print(f"  radius  n {len(dr):3d}  median signed error {statistics.median(dr):+.3f} px")
    line = bound_line(folder, truth, ok)
    if line:
        print(line)
    misread = []
    for r in ok:
        worst = None
        for k in ["psi", "delta1", "delta2", "theta1", "theta2"]:
            tv, mv, sd = truth[r["file"]][f"{k}_deg"], r[f"{k}_deg"], r[f"{k}_err_deg"]
            if tv == "" or mv == "" or sd == "":
                continue
            e = angle_error(float(mv), float(tv))
            if e > 1.0 and e > 5.0 * float(sd) and (worst is None or e > worst[1]):
                worst = (k, e, e / float(sd))
        if worst:
            misread.append(f"{r['file']} ({worst[0]} {worst[1]:.1f} deg, {worst[2]:.0f} sigma)")
    print(f"  misread {len(misread)}" + (": " + ", ".join(misread) if misread else ""))
    materials = sorted({t["material"] for t in truth.values()})
    if len(materials) > 1:
        for m in materials:
            mine = [r for r in rows if truth[r["file"]]["material"] == m]
            mine_ok = [r for r in mine if r["status"] == "ok"]
            radius = statistics.median(float(truth[r["file"]]["ball_radius_px"]) for r in mine)
            parts = []
            for k in ["psi", "theta1", "theta2", "delta1"]:
                errs = [angle_error(float(r[f"{k}_deg"]), float(truth[r["file"]][f"{k}_deg"]))
                        for r in mine_ok
                        if r[f"{k}_deg"] != "" and truth[r["file"]][f"{k}_deg"] != ""]
                parts.append(f"{k} {statistics.median(errs):.3f} ({len(errs)})" if errs else f"{k} -")
            print(f"  {m:8s} R {radius:5.1f} px  {len(mine_ok)}/{len(mine)} ok  median |error| "
                  + "  ".join(parts))


args = sys.argv[1:]
if len(args) < 2 or len(args) % 2:
    sys.exit(__doc__)
for folder, table in zip(args[::2], args[1::2]):
    report(folder, table)
