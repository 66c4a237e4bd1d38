#!/usr/bin/env python3
"""Errors of navd's own registrations against the simulator's truth (docs/performance.md
"Vision in the loop").

usage: scripts/vision-link-truth.py DIVE_DIR REPLAY_OUT_DIR

DIVE_DIR: a dive of `navtool simulate --render-images` (images.csv: true body pose at each
frame; config.yaml: the camera mount). REPLAY_OUT_DIR: `navtool replay DIVE --vision --out`
(vision_answers.csv, links.csv). For every successful answer, the true 5-dof measurement of
core CameraRelativePoseModel (azimuth, elevation of the baseline in camera i, relative roll,
pitch, heading of camera j in camera i, Smith-Self-Cheeseman compounding with the mount) and
d2 = e^T C^-1 e of the error e (angles wrapped) under the answer's covariance C. Prints one JSON
line: answers, successful, accepted links, and how many of each exceed chi2(5 dof, 99.9 %);
with the inliers and max_leverage columns, the accepted links and those beyond by bins of each.
"""
import csv
import json
import math
import sys

import yaml

CHI2_5_999 = 20.515  # chi-square quantile, 5 dof, 0.999


def rot(r, p, h):
    cr, sr, cp, sp, ch, sh = (math.cos(r), math.sin(r), math.cos(p), math.sin(p),
                              math.cos(h), math.sin(h))
    return [[ch * cp, ch * sp * sr - sh * cr, ch * sp * cr + sh * sr],
            [sh * cp, sh * sp * sr + ch * cr, sh * sp * cr - ch * sr],
            [-sp, cp * sr, cp * cr]]


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def tr(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def apply(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def compose(x1, x2):
    """x1 (+) x2 as (t, R)."""
    t1, r1 = x1
    t2, r2 = x2
    t = [a + b for a, b in zip(t1, apply(r1, t2))]
    return t, mul(r1, r2)


def true_z(pose_i, pose_j, mount):
    ci = compose(pose_i, mount)
    cj = compose(pose_j, mount)
    rt = tr(ci[1])
    t = apply(rt, [b - a for a, b in zip(ci[0], cj[0])])
    r = mul(rt, cj[1])
    roll = math.atan2(r[2][1], r[2][2])
    pitch = math.atan2(-r[2][0], math.hypot(r[0][0], r[1][0]))
    heading = math.atan2(r[1][0], r[0][0])
    return [math.atan2(t[1], t[0]), math.atan2(t[2], math.hypot(t[0], t[1])), roll, pitch,
            heading]


def solve(a, b):
    """Gaussian elimination with partial pivoting (5x5)."""
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        for r in range(c + 1, n):
            f = m[r][c] / m[c][c]
            for k in range(c, n + 1):
                m[r][k] -= f * m[c][k]
    x = [0.0] * n
    for r in reversed(range(n)):
        x[r] = (m[r][n] - sum(m[r][k] * x[k] for k in range(r + 1, n))) / m[r][r]
    return x


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


LEVERAGE_BINS = [0.0, 0.5, 0.8, 0.9, 0.95]  # lower edges
INLIER_BINS = [0, 30, 60, 120]


def count(bins, edges, value, bad):
    """[accepted, beyond] of the bin whose lower edge is the largest one <= value."""
    edge = max(e for e in edges if e <= value) if value >= edges[0] else edges[0]
    bins[edge][0] += 1
    bins[edge][1] += bad


def main(dive, out):
    cfg = yaml.safe_load(open(f"{dive}/config.yaml"))
    cam = next(s for s in cfg["sensors"] if s["type"].startswith("camera"))
    rot_deg = cam.get("mount", {}).get("rotation_deg", [0, 0, 0])
    lever = cam.get("mount", {}).get("lever_arm_m", [0, 0, 0])
    mount = (lever, rot(*[math.radians(d) for d in rot_deg]))
    poses = {}
    for row in csv.DictReader(open(f"{dive}/images.csv")):
        poses[int(row["frame_id"])] = ([float(row["x_m"]), float(row["y_m"]), float(row["z_m"])],
                                       rot(float(row["roll_rad"]), float(row["pitch_rad"]),
                                           float(row["heading_rad"])))
    accepted = {(int(r["frame_i"]), int(r["frame_j"]))
                for r in csv.DictReader(open(f"{out}/links.csv")) if r["outcome"] == "accepted"}
    n = ok = bad_ok = n_acc = bad_acc = 0
    by_leverage = {b: [0, 0] for b in LEVERAGE_BINS}
    by_inliers = {b: [0, 0] for b in INLIER_BINS}
    for r in csv.DictReader(open(f"{out}/vision_answers.csv")):
        n += 1
        if r["success"] != "1":
            continue
        ok += 1
        i, j = int(r["frame_i"]), int(r["frame_j"])
        z = [float(r[f"z{k}"]) for k in range(5)]
        c = [[float(r[f"c{a}{b}"]) for b in range(5)] for a in range(5)]
        zt = true_z(poses[i], poses[j], mount)
        e = [wrap(a - b) for a, b in zip(z, zt)]
        d2 = sum(a * b for a, b in zip(e, solve(c, e)))
        bad = d2 > CHI2_5_999
        bad_ok += bad
        if (i, j) in accepted:
            n_acc += 1
            bad_acc += bad
            if "max_leverage" in r:
                count(by_leverage, LEVERAGE_BINS, float(r["max_leverage"]), bad)
                count(by_inliers, INLIER_BINS, int(r["inliers"]), bad)
    print(json.dumps({"answers": n, "successful": ok, "successful_beyond_999": bad_ok,
                      "accepted": n_acc, "accepted_beyond_999": bad_acc,
                      "accepted_beyond_999_fraction": bad_acc / n_acc if n_acc else None,
                      "accepted_by_max_leverage_from": {str(b): v for b, v in by_leverage.items()},
                      "accepted_by_inliers_from": {str(b): v for b, v in by_inliers.items()}}))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
