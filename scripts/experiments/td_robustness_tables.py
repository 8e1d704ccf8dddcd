#!/usr/bin/env python3
"""Tables of scripts/experiments/td_robustness.sh from its runs.csv: OUT/table.md (every run) and OUT/summary.md (per
data set and mode: the time each start took to stay within 1 ms of the truth, or how it ended).
Usage: td_robustness_tables.py RUNS_CSV OUT_DIR COMMIT DURATION_S"""
import csv
import sys

runs, out_dir, commit, dur = sys.argv[1:5]
rows = list(csv.DictReader(open(runs)))
made = f"Made by `scripts/experiments/td_robustness.sh OUT {dur}` at commit {commit}.\n\n"

with open(f"{out_dir}/table.md", "w") as out:
    out.write(made)
    out.write("| data | mode | t_d search | true t_d [ms] | start [ms] | exit | search found [ms] | final t̂_d [ms] | "
              "σ [ms] | within 1 ms after [s] | wall [s] | APE [m] |\n")
    out.write("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    for r in rows:
        out.write(f"| {r['dataset']} | {r['mode']} | {r['search']} | {r['td_true_ms']} | {r['td_init_ms']} | "
                  f"{r['exit']} | {r['search_ms']} | {r['final_td_ms']} | {r['final_sigma_ms']} | "
                  f"{r['converged_after_s']} | {r['wall_s']} | {r['ape_m']} |\n")


def cell(r):
    if r["exit"] != "0":
        return f"exit {r['exit']}"
    conv = r["converged_after_s"]
    return f"{conv} s" if conv != "never" else f"**wrong**: {r['final_td_ms']} ms"


with open(f"{out_dir}/summary.md", "w") as out:
    out.write(made)
    out.write("Each cell: seconds of data until t̂_d stays within 1 ms of the truth (0 s: the search already put it "
              "there), or the exit code of a run that stopped (4: the filter's health check).\n\n")
    groups = {}
    for r in rows:
        err = round(float(r["td_init_ms"]) - float(r["td_true_ms"]))
        groups.setdefault((r["dataset"], r["mode"], r["search"], r["td_true_ms"]), {})[err] = r
    errs = sorted({e for g in groups.values() for e in g})
    out.write("| data | true t_d [ms] | mode | search | " + " | ".join(f"error at start {e:+d} ms" for e in errs) +
              " | search found [ms] | final t̂_d [ms] | wall per run [s] |\n")
    out.write("|---|---:|---|---|" + "---:|" * len(errs) + "---|---|---|\n")
    for (data, mode, search, truth), g in groups.items():
        found = sorted({r["search_ms"] for r in g.values() if r["search_ms"]})
        finals = [float(r["final_td_ms"]) for r in g.values() if r["exit"] == "0" and r["final_td_ms"]]
        walls = [float(r["wall_s"]) for r in g.values()]
        out.write(f"| {data} | {truth} | {mode} | {search} | " +
                  " | ".join(cell(g[e]) if e in g else "" for e in errs) + " | " +
                  (f"{found[0]}-{found[-1]}" if found else "-") + " | " +
                  (f"{min(finals):.2f}-{max(finals):.2f}" if finals else "-") + " | " +
                  f"{min(walls):.0f}-{max(walls):.0f} |\n")
