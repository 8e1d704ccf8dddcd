#!/usr/bin/env python3
"""The accuracy gate's arithmetic (scripts/accuracy_gate.sh drives the runs; docs/accuracy_gate.md).

  accuracy_gate.py calibrate REF.csv BASE.csv NUISANCE.csv...   write the references and their tolerances
  accuracy_gate.py check REF.csv NOW.csv                         compare a run with them; exit 1 on a regression

A metric's tolerance is max(3 x its spread over the nuisance variants, a floor); the floor is the larger of an
absolute one per metric and 5 % of the reference, so that a change that makes a case 20 % worse cannot hide in it.
Only a worsening beyond the tolerance (or a mode that no longer finishes) fails; an improvement beyond it is reported
so that the references get updated with the change that earned it.
"""
import csv
import statistics
import sys

METRICS = ("ape_mm", "tpe_mm", "td_err_ms")
ABS_FLOOR = {"ape_mm": 0.5, "tpe_mm": 0.05, "td_err_ms": 0.05}
REL_FLOOR = 0.05


def read_rows(path):
    with open(path) as f:
        return {(r["case"], r["mode"]): r for r in csv.DictReader(f)}


def calibrate(ref_path, base_path, nuisance_paths):
    base = read_rows(base_path)
    variants = [read_rows(p) for p in nuisance_paths]
    out = []
    for key, row in sorted(base.items()):
        if row["status"] != "ok":
            sys.exit(f"accuracy_gate: {key[0]} {key[1]} did not finish ({row['status']}): no reference from it")
        for m in METRICS:
            values = [float(row[m])] + [float(v[key][m]) for v in variants if key in v]
            spread = statistics.pstdev(values)
            ref = float(row[m])
            tol = max(3 * spread, ABS_FLOOR[m], REL_FLOOR * abs(ref))
            out.append((key[0], key[1], m, ref, spread, min(values), max(values), tol))
    with open(ref_path, "w") as f:
        f.write("# scripts/accuracy_gate.sh --calibrate: reference = the unperturbed run; spread = standard deviation over\n"
                "# it and 4 nuisance variants (update.sigma_px x 1 +- 1e-4, 2e-4); tolerance = max(3 x spread, floor)\n")
        f.write("case,mode,metric,reference,spread,min,max,tolerance\n")
        for r in out:
            f.write("%s,%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f\n" % r)
    print(f"accuracy_gate: {len(out)} references written to {ref_path}")
    print_table(["case", "mode", "metric", "reference", "spread", "min", "max", "tolerance"],
                [[a, b, c] + ["%.3f" % x for x in rest] for a, b, c, *rest in out])


def check(ref_path, now_path):
    with open(ref_path) as f:
        refs = list(csv.DictReader(line for line in f if not line.startswith("#")))
    now = read_rows(now_path)
    rows, worse, better = [], 0, 0
    for r in refs:
        key = (r["case"], r["mode"])
        ref, tol = float(r["reference"]), float(r["tolerance"])
        if key not in now:
            if r["case"].startswith("cut_"):
                continue  # the real cut is absent on this machine (said above); nothing to compare
            rows.append([*key, r["metric"], "%.3f" % ref, "-", "-", "%.3f" % tol, "MISSING"])
            worse += 1
            continue
        n = now[key]
        if n["status"] != "ok":
            rows.append([*key, r["metric"], "%.3f" % ref, n["status"], "-", "%.3f" % tol, "FAILED"])
            worse += 1
            continue
        value = float(n[r["metric"]])
        change = value - ref
        verdict = "ok"
        if change > tol:
            verdict, worse = "WORSE", worse + 1
        elif change < -tol:
            verdict, better = "better", better + 1
        rows.append([*key, r["metric"], "%.3f" % ref, "%.3f" % value, "%+.3f" % change, "%.3f" % tol, verdict])
    print_table(["case", "mode", "metric", "reference", "now", "change", "tolerance", "verdict"], rows)
    if better:
        print(f"accuracy_gate: {better} metric(s) better than the reference by more than the tolerance: if the change "
              "is meant, update the references (scripts/accuracy_gate.sh --calibrate)")
    if worse:
        print(f"accuracy_gate: FAILED: {worse} of {len(rows)} metric(s) worse than the reference by more than the "
              "tolerance (docs/accuracy_gate.md)")
        return 1
    print(f"accuracy_gate: passed: {len(rows)} metrics within tolerance of {ref_path}")
    return 0


def print_table(header, rows):
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for r in rows:
        print("| " + " | ".join(str(x) for x in r) + " |")


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "calibrate":
        calibrate(sys.argv[2], sys.argv[3], sys.argv[4:])
    elif len(sys.argv) == 4 and sys.argv[1] == "check":
        sys.exit(check(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)
