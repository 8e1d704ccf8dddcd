#!/usr/bin/env python3
"""One estimator run of the protocol workflow: `ovton run` on a folder in one mode, then `ovton eval`, written as one
JSON record. A run that fails or diverges is a result, not a workflow error: its record says so (status), so the
tables show it and the other cells still finish."""
import argparse
import json
import os
import re
import subprocess
import sys
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ovton", required=True)
    ap.add_argument("--dataset", required=True)
    ap.add_argument("--mode", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    base = os.path.splitext(a.out)[0]
    traj, eval_json, log = base + ".csv", base + "_eval.json", base + ".log"
    rec = {"dataset": a.dataset, "mode": a.mode, "config": a.config, "status": "ok"}
    t0 = time.time()
    run = subprocess.run([a.ovton, "run", "--dataset", a.dataset, "--config", a.config, "--td-mode", a.mode,
                          "--output", traj, "-q", "--no-prefetch"], capture_output=True, text=True)
    rec["wall_s"] = time.time() - t0
    with open(log, "w") as f:
        f.write(run.stdout + run.stderr)
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or ["exit code %d" % run.returncode])[-1]
        rec["status"] = "failed: " + last
    m = re.search(r"per frame \[ms\]: image load ([\d.]+), tracking ([\d.]+), propagation ([\d.]+), update ([\d.]+);"
                  r" ([\d.]+)x real time", run.stdout)
    if m:
        rec.update(load_ms=float(m[1]), tracking_ms=float(m[2]), propagation_ms=float(m[3]), update_ms=float(m[4]),
                   realtime=float(m[5]))
    m = re.search(r"networks ([\d.]+) ms/frame", run.stdout)
    if m:
        rec["networks_ms"] = float(m[1])
    if os.path.exists(traj) and os.path.getsize(traj) > 0:
        gt = os.path.join(a.dataset, "mav0/state_groundtruth_estimate0/data.csv")
        td = os.path.join(a.dataset, "mav0/td_truth/data.csv")
        ev = subprocess.run([a.ovton, "eval", "--est", traj, "--gt", gt, "--td-truth", td, "--json", eval_json],
                            capture_output=True, text=True)
        if ev.returncode == 0:
            e = json.load(open(eval_json))
            for k in ["ape_rmse_m", "are_rmse_deg", "tpe_rmse_mm", "td_err_rmse_ms", "td_err_rmse_late_ms", "td_nees",
                      "cit", "n_matched"]:
                rec[k] = e.get(k)
        elif rec["status"] == "ok":
            rec["status"] = "not evaluated: " + (ev.stderr.strip().splitlines() or ["?"])[-1]
        rows = [l for l in open(traj) if l[:1].isdigit()]
        if rows:
            rec["final_td_ms"] = float(rows[-1].split(",")[17]) * 1e3
    elif rec["status"] == "ok":
        rec["status"] = "failed: no trajectory"
    with open(a.out, "w") as f:
        json.dump(rec, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
