#!/usr/bin/env bash
# Issue 36: `ovton diagnose` on real EuRoC data with nothing planted, and with a drifting offset planted in the real
# images' stamps. The moving V1_01 cut (4.45 s in flight) and the micro folder (still on the ground, static
# initialisation) as they are; the cut's image stamps perturbed with `ovton perturb --td-model drift --td0-ms 0` at each
# rate of RATES (the paper's model: the rate plus a 0.1 ms/sqrt(s) random walk, seed 1), not declared to the run. Every
# run `ovton run --td-mode sr` with config/euroc_mav (ground-truth initialisation on the cut, static on the micro folder)
# and a residual log, then `ovton diagnose --dataset`. Prints and writes OUT/real.md: per folder the first flagged
# candidate and the time candidates' estimates; for the drifted cuts also what there was to find (the least-squares
# slope of the true offset over the cut: the random walk is as large as a slow drift over 4.45 s) and how far `sr`'s
# own t̂_d moved from 2 s to the end against what its reported sigma lets the estimate of a constant move,
# sqrt(sigma(2 s)^2 - sigma(end)^2) (docs/diagnose_undeclared.md, "Real data and short flights").
# Usage: scripts/experiments/diagnose_real.sh OUT   (~30 s)
#   RATES (default "0.1 0.5 1 2 3" ms/s), OVTON_BIN.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: diagnose_real.sh OUT}
RATES=${RATES:-"0.1 0.5 1 2 3"}
BIN=${OVTON_BIN:-$(pwd)/build/ovton}
[ -x "$BIN" ] || scripts/build.sh
DATA=../shared/data
CFG=config/euroc_mav/estimator_config.yaml
mkdir -p "$OUT"
one() { # name folder init
  local d="$OUT/$1"
  mkdir -p "$d"
  nice -n 10 "$BIN" run --dataset "$2" --config "$CFG" --td-mode sr --init "$3" --output "$d/run.csv" \
    --residual-log "$d/res.csv" -q >"$d/run.txt" 2>&1
  nice -n 10 "$BIN" diagnose --log "$d/res.csv" --dataset "$2" --out "$d/diagnose" >"$d/diagnose.txt"
  python3 - "$d/diagnose/diagnose.json" "$1" "$d/run.csv" "$2/mav0/td_truth/data.csv" <<'PY'
import csv, json, math, os, sys
d = json.load(open(sys.argv[1]))
first = next((c for c in d["candidates"] if c["explained"]), None)
flag = "nothing" if first is None else first["key"]
if d.get("not_testable"):
    flag = "nothing testable: " + d["not_testable"]
def est(key):
    c = next((c for c in d["candidates"] if c["key"] == key), None)
    if not c or not c["estimates"]:
        return "-"
    e = c["estimates"][0]
    v = "EXPLAINED" if c["explained"] else ("not testable" if not c.get("testable", True) else "not explained")
    return f"{e['value']:.3g} ± {e['stderr']:.2g} {e['unit']} ({c['sigma']:.1f}σ, {v})"
flagged = [c["key"] for c in d["candidates"] if c["explained"]]
untestable = [c["key"] for c in d["candidates"] if not c.get("testable", True)]
def slope(ts, ys):
    n = len(ts)
    if n < 2:
        return float("nan")
    mt, my = sum(ts) / n, sum(ys) / n
    return sum((t - mt) * (y - my) for t, y in zip(ts, ys)) / sum((t - mt) ** 2 for t in ts)
truth = "-"
if os.path.exists(sys.argv[4]):
    rows = [r for r in csv.reader(open(sys.argv[4])) if r and not r[0].startswith("#")]
    t0 = int(rows[0][0])
    truth = f"{slope([1e-9 * (int(r[0]) - t0) for r in rows], [1e3 * float(r[1]) for r in rows]):.3f} ms/s"
moved = "-"
if os.path.exists(sys.argv[3]):
    run = list(csv.DictReader(open(sys.argv[3])))
    if run:
        t0 = int(run[0]["timestamp_ns"])
        i = next((k for k, r in enumerate(run) if 1e-9 * (int(r["timestamp_ns"]) - t0) >= 2.0), len(run) - 1)
        a, b = run[i], run[-1]
        sa, sb = 1e3 * float(a["td_sigma_s"]), 1e3 * float(b["td_sigma_s"])
        allowed = math.sqrt(max(sa * sa - sb * sb, 0.0))
        dm = 1e3 * (float(b["td_s"]) - float(a["td_s"]))
        moved = f"{dm:+.2f} ms ({dm / allowed:.1f} sd of {allowed:.2f})" if allowed > 0 else f"{dm:+.2f} ms"
print(f"| {sys.argv[2]} | {flag} | {', '.join(flagged) or '-'} | {truth} | {est('td_drift')} | {moved} | "
      f"{est('td_piecewise')} | {est('extrinsic_translation')} | {len(untestable)} |")
PY
}
{
  echo "# diagnose on real EuRoC data"
  echo
  echo "Made by \`scripts/experiments/diagnose_real.sh $OUT\` at commit $(git rev-parse --short HEAD)."
  echo
  echo "| folder | first flagged | all flagged | true offset's slope | td_drift: drift rate | sr's t̂_d from 2 s to" \
    "the end | td_piecewise: spread | extrinsic_translation | not testable |"
  echo "|---|---|---|---|---|---|---|---|---:|"
  one cut "$DATA/euroc_v1_01_moving" groundtruth
  one micro "$DATA/euroc_v1_01_micro" static
  for R in $RATES; do
    rm -rf "$OUT/drift_$R/data"
    mkdir -p "$OUT/drift_$R"
    "$BIN" perturb --dataset "$DATA/euroc_v1_01_moving" --out "$OUT/drift_$R/data" --td-model drift --td0-ms 0 \
      --td-bias-ms-per-s "$R" --seed 1 >/dev/null
    one "drift_$R" "$OUT/drift_$R/data" groundtruth
  done
} | tee "$OUT/real.md"
