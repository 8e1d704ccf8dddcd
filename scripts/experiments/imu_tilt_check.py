#!/usr/bin/env python3
"""Is the real IMU log's slow accelerometer error an attitude disagreement with the ground truth? (issue 13)

If the ground truth's attitude were off the IMU's by a slowly varying δθ(t), the gyro against the ground truth would
read δθ̇ and the accelerometer f × δθ (f the specific force in the body frame), so the accelerometer's slow residual
would follow the gyro's integrated one. This fits that prediction per axis in a frequency band.

  /usr/bin/python3 scripts/experiments/imu_tilt_check.py [FOLDER] [LOW_HZ HIGH_HZ]

FOLDER: an EuRoC folder with imu0 and state_groundtruth_estimate0 (default ../shared/data/euroc_v1_01_moving);
band default 0.1-1 Hz. Needs numpy and scipy (Debian: python3-numpy python3-scipy).
"""
import os
import sys

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation, Slerp


def band(x, dt, lo, hi):
    X = np.fft.rfft(x - x.mean(0), axis=0)
    f = np.fft.rfftfreq(len(x), dt)
    X[(f < lo) | (f > hi)] = 0
    return np.fft.irfft(X, n=len(x), axis=0)


def main():
    repo = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.join(repo, "..", "shared", "data", "euroc_v1_01_moving")
    lo = float(sys.argv[2]) if len(sys.argv) > 2 else 0.1
    hi = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
    imu = np.loadtxt(os.path.join(folder, "mav0/imu0/data.csv"), delimiter=",", comments="#")
    gt = np.loadtxt(os.path.join(folder, "mav0/state_groundtruth_estimate0/data.csv"), delimiter=",", comments="#")
    tg = (gt[:, 0] - gt[0, 0]) * 1e-9
    ti = (imu[:, 0] - gt[0, 0]) * 1e-9
    keep = (ti > tg[0] + 0.5) & (ti < tg[-1] - 0.5)
    ti, imu = ti[keep], imu[keep]
    att = Slerp(tg, Rotation.from_quat(gt[:, [5, 6, 7, 4]]))  # x y z w
    h = 0.01
    w_gt = (att(np.clip(ti - h, tg[0], tg[-1])).inv() * att(np.clip(ti + h, tg[0], tg[-1]))).as_rotvec() / (2 * h)
    a_w = CubicSpline(tg, gt[:, 1:4])(ti, 2)
    f_gt = att(ti).inv().apply(a_w - np.array([0, 0, -9.81]))
    b_w = np.array([np.interp(ti, tg, gt[:, 11 + k]) for k in range(3)]).T
    b_a = np.array([np.interp(ti, tg, gt[:, 14 + k]) for k in range(3)]).T
    e_g = imu[:, 1:4] - b_w - w_gt
    e_a = imu[:, 4:7] - b_a - f_gt
    dt = float(np.median(np.diff(ti)))
    tilt = band(np.cumsum(e_g, axis=0) * dt, dt, lo, hi)
    e_ab = band(e_a, dt, lo, hi)
    pred = band(np.cross(f_gt, tilt), dt, lo, hi)
    print(f"{folder}: {ti[-1] - ti[0]:.1f} s, band {lo}-{hi} Hz; gyro-integrated tilt RMS [deg] "
          + ", ".join(f"{v:.3f}" for v in np.degrees(tilt.std(0))))
    print("| accel axis | residual RMS [m/s²] | predicted f × δθ RMS | slope | R² | correlation |")
    print("|---|---:|---:|---:|---:|---:|")
    for k, n in enumerate("xyz"):
        a, p = e_ab[:, k], pred[:, k]
        s = p @ a / (p @ p)
        r2 = 1 - ((a - s * p) ** 2).sum() / (a ** 2).sum()
        print(f"| {n} | {a.std():.4f} | {p.std():.4f} | {s:.2f} | {r2:.2f} | {np.corrcoef(a, p)[0, 1]:.2f} |")


if __name__ == "__main__":
    main()
