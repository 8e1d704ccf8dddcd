#!/usr/bin/env python3
"""ovton on EuRoC folders with config keys overridden: APE, ARE, NEES (orientation, position, t_d), features per
frame and CPU time, one line per folder (docs/peer.md, "What the gap was made of").

  scripts/peer/config_sweep.py --name imu2 --set imu.noise_multiplier=2 FOLDER...

Simulated folders (with mav0/td_truth) start from config/sim/estimator_config.yaml, real ones from
config/euroc_mav/estimator_config.yaml; every run uses --init groundtruth (NEES needs it), --no-prefetch and one
OpenCV thread, under nice -n 10, one at a time. Lines are also appended to OUT/results.txt.
"""
import argparse
import csv
import os
import re
import subprocess

import sys

import yaml

REPO = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "scripts"))
from config_override import apply_overrides  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--name", required=True, help="label of this variant (file names, output lines)")
    ap.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE", help="config override")
    ap.add_argument("--bin", default=os.path.join(REPO, "build", "ovton"))
    ap.add_argument("--out", default="/tmp/ovton_sweep")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for folder in a.folders:
        folder = os.path.realpath(folder)
        sim = os.path.isdir(os.path.join(folder, "mav0", "td_truth"))
        cfg = yaml.safe_load(open(os.path.join(REPO, "config", "sim" if sim else "euroc_mav", "estimator_config.yaml")))
        apply_overrides(cfg, a.set)
        pre = os.path.join(a.out, f"{a.name}_{os.path.basename(folder)}")
        yaml.safe_dump(cfg, open(pre + ".yaml", "w"))
        cmd = ["nice", "-n", "10", "/usr/bin/time", "-f", "%U %S", "-o", pre + ".time", a.bin, "run", "-q",
               "--no-prefetch", "-d", folder, "-c", pre + ".yaml", "-o", pre + ".csv", "--init", "groundtruth",
               "--nees-log", pre + "_nees.csv"]
        log = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OPENCV_FOR_THREADS_NUM="1")).stdout
        open(pre + ".log", "w").write(log)
        ape = re.search(r"APE ([0-9.]+) m, ARE ([0-9.]+)", log)
        nees = re.search(r"NEES orientation ([0-9.]+), position ([0-9.]+)", log)
        used = re.search(r"mode [^:]*: (\d+) images.* (\d+) features used", log)
        if not (ape and nees and used):
            line = f"{a.name} {os.path.basename(folder)}: FAILED (log {pre}.log)"
        else:
            rows = list(csv.DictReader(open(pre + "_nees.csv")))
            td = [float(r["nees_td"]) for r in rows if r.get("nees_td") not in (None, "", "nan")]
            td_nees = f"{sum(td) / len(td):.2f}" if td else "-"
            cpu = sum(float(x) for x in open(pre + ".time").read().split()[-2:])
            line = (f"{a.name} {os.path.basename(folder)}: APE {float(ape.group(1)) * 1e3:.0f} mm ARE {ape.group(2)} "
                    f"NEES {nees.group(1)}/{nees.group(2)}/td {td_nees} "
                    f"feat/frame {int(used.group(2)) / int(used.group(1)):.1f} cpu {cpu:.1f}")
        print(line, flush=True)
        with open(os.path.join(a.out, "results.txt"), "a") as f:
            f.write(line + "\n")


if __name__ == "__main__":
    main()
