#!/usr/bin/env python3
"""Where an accelerometer scale goes in the filter (issue 36, docs/diagnose_undeclared.md "Real data"): rewrites a
calibration log's IMU state (q_WB and/or v_W at t_imu_ns) with the ground truth's, linearly interpolated (quaternions
normalised), so that `ovton diagnose --calibration-log OUT` reads the accelerometer design through the true attitude,
velocity or both.

Usage: accel_true_states.py CALIB_CSV GROUNDTRUTH_CSV OUT_CSV [both|att|vel]
"""
import bisect
import csv
import math
import sys


def main():
    cal, gt, out = sys.argv[1:4]
    which = sys.argv[4] if len(sys.argv) > 4 else "both"
    truth = [r for r in csv.reader(open(gt)) if r and not r[0].startswith("#")]
    stamps = [int(r[0]) for r in truth]
    rows = list(csv.reader(open(cal)))
    ix = {k: i for i, k in enumerate(rows[0])}
    for r in rows[1:]:
        t = int(r[ix["t_imu_ns"]])
        i = min(max(1, bisect.bisect_left(stamps, t)), len(stamps) - 1)
        a, b = truth[i - 1], truth[i]
        u = (t - stamps[i - 1]) / (stamps[i] - stamps[i - 1])
        q = [(1 - u) * float(a[4 + k]) + u * float(b[4 + k]) for k in range(4)]
        n = math.sqrt(sum(x * x for x in q))
        v = [(1 - u) * float(a[8 + k]) + u * float(b[8 + k]) for k in range(3)]
        if which in ("att", "both"):
            for k, name in enumerate(["q_WB_w", "q_WB_x", "q_WB_y", "q_WB_z"]):
                r[ix[name]] = repr(q[k] / n)
        if which in ("vel", "both"):
            for k in range(3):
                r[ix["v_W_%d" % k]] = repr(v[k])
    csv.writer(open(out, "w", newline="")).writerows(rows)


if __name__ == "__main__":
    main()
