#!/usr/bin/env python3
"""A prototype of the accelerometer's scale against gravity from the filter's POSITIONS instead of its velocity (issue
36, docs/diagnose_undeclared.md "Real data"): over windows of +-N images, the position's second difference
(p_b - p_c)/T2 - (p_c - p_a)/T1 = integral of K(t)*a_W(t), K the triangle kernel, against the accelerometer through
the filter's attitude at the window's centre carried by the gyro (less the filter's bias):
    K*R*a_m/(1 + s) - K*R*b + K*g = (second difference)/mu,
the trajectory's own scale mu and a body-frame bias per bin projected out, s from the remaining column (one cluster per
window). Reads the trajectory CSV `ovton run` writes (positions and attitude per image, IMU clock) and the folder's
imu0/data.csv; --truth GT_CSV takes positions and attitude from the ground truth at the same stamps instead.

Usage: accel_position_design.py RUN_CSV IMU_CSV [--half-images N (10)] [--bin-s S (5)] [--truth GT_CSV]
"""
import argparse
import bisect
import csv

import numpy as np


def rows_of(path):
    return [r for r in csv.reader(open(path)) if r and r[0][0].isdigit()]


def qmat(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def so3_exp(v):
    th = np.linalg.norm(v)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    if th < 1e-12:
        return np.eye(3) + k
    return np.eye(3) + np.sin(th) / th * k + (1 - np.cos(th)) / th ** 2 * k @ k


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("imu")
    ap.add_argument("--half-images", type=int, default=10)
    ap.add_argument("--bin-s", type=float, default=5.0)
    ap.add_argument("--truth")
    a = ap.parse_args()
    run = np.array([[float(x) for x in r[:14]] for r in rows_of(a.run)])
    t = np.array([int(r[0]) for r in rows_of(a.run)], dtype=np.int64)
    pos, quat, bg = run[:, 1:4], run[:, 4:8], run[:, 11:14]
    if a.truth:  # positions and attitude of the ground truth at the run's stamps
        gt = rows_of(a.truth)
        gs = [int(r[0]) for r in gt]
        for j, tj in enumerate(t):
            i = min(max(1, bisect.bisect_left(gs, tj)), len(gs) - 1)
            u = (tj - gs[i - 1]) / (gs[i] - gs[i - 1])
            v = [(1 - u) * float(gt[i - 1][k]) + u * float(gt[i][k]) for k in range(1, 8)]
            pos[j], quat[j] = v[0:3], v[3:7]
    imu = rows_of(a.imu)
    ti = np.array([int(r[0]) for r in imu], dtype=np.int64)
    gyro = np.array([[float(x) for x in r[1:4]] for r in imu])
    acc = np.array([[float(x) for x in r[4:7]] for r in imu])
    g = np.array([0.0, 0.0, -9.81])
    n = a.half_images
    wins = []
    for c in range(n, len(t) - n, 2 * n):
        ta, tc, tb = t[c - n], t[c], t[c + n]
        t1, t2 = (tc - ta) * 1e-9, (tb - tc) * 1e-9
        d2 = (pos[c + n] - pos[c]) / t2 - (pos[c] - pos[c - n]) / t1
        idx = np.nonzero((ti >= ta) & (ti <= tb))[0]
        k0 = np.searchsorted(ti, tc)
        att = {}
        r = qmat(quat[c])
        for k in range(k0, idx[-1] + 1):
            att[k] = r
            if k + 1 < len(ti):
                r = r @ so3_exp((gyro[k] - bg[c]) * (ti[k + 1] - ti[k]) * 1e-9)
        r = qmat(quat[c])
        for k in range(k0 - 1, idx[0] - 1, -1):
            r = r @ so3_exp(-(gyro[k] - bg[c]) * (ti[k + 1] - ti[k]) * 1e-9)
            att[k] = r
        x, b, gg = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros(3)
        for k in idx[:-1]:
            h = (ti[k + 1] - ti[k]) * 1e-9
            tm = 0.5 * (ti[k] + ti[k + 1])
            kern = (tm - ta) * 1e-9 / t1 if tm <= tc else (tb - tm) * 1e-9 / t2
            x += kern * h * att[k] * (0.5 * (acc[k] + acc[k + 1]))[None, :]
            b += kern * h * att[k]
            gg += kern * h * g
        wins.append(((tc - t[0]) * 1e-9, d2, x, b, gg))
    tmax = wins[-1][0]
    nb = max(1, int(round(tmax / a.bin_s)))
    nw = len(wins)
    data, col, nuis = np.zeros(3 * nw), np.zeros(3 * nw), np.zeros((3 * nw, 1 + 3 * nb))
    for w, (tc, d2, x, b, gg) in enumerate(wins):
        bi = min(nb - 1, int(nb * tc / max(1e-9, tmax)))
        data[3 * w:3 * w + 3] = x.sum(axis=1) + gg - d2
        col[3 * w:3 * w + 3] = x.sum(axis=1)
        nuis[3 * w:3 * w + 3, 0] = d2
        nuis[3 * w:3 * w + 3, 1 + 3 * bi:4 + 3 * bi] = b
    proj = nuis @ np.linalg.lstsq(nuis, np.column_stack([data, col]), rcond=None)[0]
    rr, xx = data - proj[:, 0], col - proj[:, 1]
    beta = xx @ rr / (xx @ xx)
    e = rr - beta * xx
    scores = np.array([xx[3 * w:3 * w + 3] @ e[3 * w:3 * w + 3] for w in range(nw)])
    se = np.sqrt(nw / (nw - 1) * (scores @ scores)) / (xx @ xx)
    kappa = 1 - beta
    print(f"windows {nw} (+-{n} images), bias bins {nb}: s = {100 * beta / kappa:.2f} ± {100 * se / kappa ** 2:.2f} %")


if __name__ == "__main__":
    main()
