#!/usr/bin/env python3
"""Assembles the protocol's `ovton compare` results into the paper's table layouts (see protocol.sh)."""
import csv
import os
import sys

out, quick, commit = sys.argv[1], sys.argv[2] == "1", sys.argv[3]
SEQS = ["MH_03_medium", "MH_04_difficult", "MH_05_difficult", "V1_02_medium", "V1_03_difficult", "V2_02_medium",
        "V2_03_difficult"]
SHORT = {"MH_03_medium": "MH_03_M", "MH_04_difficult": "MH_04_M", "MH_05_difficult": "MH_05_M",
         "V1_02_medium": "V1_02_H", "V1_03_difficult": "V1_03_H", "V2_02_medium": "V2_02_H", "V2_03_difficult": "V2_03_H"}
data = "feature-level folders, 0.3 px noise, 30 s" if quick else "rendered 752x480 folders, real KLT front end, 60 s"


def load(name):
    path = os.path.join(out, name, "results.csv")
    if not os.path.exists(path):
        return {}
    return {r["mode"]: r for r in csv.DictReader(open(path))}


def cell(r, key, fmt):
    if not r or r.get("status") != "ok" or r.get(key) in (None, ""):
        return "–"
    v = float(r[key])
    return "never" if key == "cit_frames" and v < 0 else fmt.format(v)


with open(os.path.join(out, "table3.md"), "w") as f:
    f.write("# Table III layout: RMSE of TPE [mm] and APE [m] under a drifting offset\n\n")
    env = f"PROTOCOL_CONFIG={os.environ['PROTOCOL_CONFIG']} " if os.environ.get("PROTOCOL_CONFIG") else ""
    f.write(f"Made by `{env}scripts/experiments/protocol.sh{' ' + out if out else ''}{' --quick' if quick else ''}` "
            f"(commit {commit}); {data}; drift: start 10 ms, bias 0.1 ms/s, noise n_td per sqrt(s).\n\n")
    f.write("| n_td [ms] | method | " + " | ".join(f"{SHORT[s]} TPE | {SHORT[s]} APE" for s in SEQS) + " |\n")
    f.write("|---|---|" + "---|---|" * len(SEQS) + "\n")
    for n in ["0.1", "0.125"]:
        res = {s: load(f"t3_{s}_n{n}") for s in SEQS}
        for mode in ["sr", "sir", "ton", "off", "oracle"]:
            row = [n, mode]
            for s in SEQS:
                r = res[s].get(mode)
                row += [cell(r, "tpe_rmse_mm", "{:.1f}"), cell(r, "ape_rmse_m", "{:.3f}")]
            f.write("| " + " | ".join(row) + " |\n")

with open(os.path.join(out, "table2.md"), "w") as f:
    f.write("\n# Table II design: constant offsets, CIT [frames] and APE [m]\n\n")
    f.write(f"Made by the same command (commit {commit}); {data}. CIT: |t̂_d − t_d| ≤ 1 ms and change ≤ 0.1 ms.\n\n")
    f.write("| sequence | t_d [ms] | sir CIT | ton CIT | sr CIT | sir APE | ton APE | sr APE |\n")
    f.write("|---|---|---|---|---|---|---|---|\n")
    for s in ["V1_03_difficult", "MH_03_medium"]:
        for td in ["-20", "-10", "10", "20"]:
            res = load(f"t2_{s}_td{td}")
            f.write(f"| {SHORT[s]} | {td} | " + " | ".join(cell(res.get(m), "cit_frames", "{:.0f}") for m in
                                                           ["sir", "ton", "sr"]) + " | " +
                    " | ".join(cell(res.get(m), "ape_rmse_m", "{:.3f}") for m in ["sir", "ton", "sr"]) + " |\n")
