#!/usr/bin/env bash
# The whole-flight cell where `sr` is stopped by the health check (docs/ton.md, Table III on whole flights): the
# protocol's V2_03_difficult rendering (drift from 10 ms at 0.1 ms/s, n_td 0.1 ms/sqrt(s), from 20 s to 1 s before the
# ground truth ends, seed 1, realism euroc), `ovton run --td-mode sr` with a residual log, then `ovton diagnose`: which
# effect the stopped run's residuals and rates show, and the offset per time bin against the truth.
# Usage: scripts/experiments/diagnose_whole_stop.sh [OUT]   (~6 min here: most of it the rendering; kept for re-runs)
#   OVTON_BIN overrides the binary; SEQ (V2_03_difficult) and NTD (0.1) choose the cell.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/diagnose_whole_stop}
BIN=${OVTON_BIN:-build/ovton}
SEQ=${SEQ:-V2_03_difficult}
NTD=${NTD:-0.1}
GT=../shared/data/euroc_groundtruth/$SEQ.txt
[ -f "$GT" ] || { echo "needs $GT (../shared beside the repository)" >&2; exit 2; }
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
DUR=$(python3 -c "import sys; s=[float(l.split()[0]) for l in open(sys.argv[1]) if l.strip() and not l.startswith('#')]; print(round(s[-1]-s[0]-20-1,1))" "$GT")
SIM=(simulate --out "$OUT/data" --gt "$GT" --td-model drift --td0-ms 10 --td-bias-ms-per-s 0.1 --td-noise-ms-per-sqrt-s "$NTD"
  --duration-s "$DUR" --start-s 20 --seed 1 --realism euroc --force -q)
[ -f "$OUT/data/sim.yaml" ] && [ -f "$OUT/.sim_args" ] && [ "$(cat "$OUT/.sim_args")" = "${SIM[*]}" ] ||
  { "$BIN" "${SIM[@]}" >/dev/null && echo "${SIM[*]}" >"$OUT/.sim_args"; }
# A stop by the health check is the case of interest: its rows and residual log are kept, its exit code is not fatal.
"$BIN" run --dataset "$OUT/data" --config config/sim/estimator_config.yaml --td-mode sr --output "$OUT/sr.csv" \
  --residual-log "$OUT/sr_res.csv" -q --no-prefetch >"$OUT/sr_run.txt" 2>&1 || echo "sr exited $? ($(tail -c 300 "$OUT/sr_run.txt"))"
"$BIN" diagnose --log "$OUT/sr_res.csv" --dataset "$OUT/data" --out "$OUT/diagnose" | tee "$OUT/diagnose.txt" | grep -E '^[1-3] '
# The per-bin offsets the data imply, beside the true offset at each bin's time.
python3 - "$OUT/diagnose/diagnose.md" "$OUT/data/mav0/td_truth/data.csv" "$OUT/sr_res.csv" <<'PY'
import csv, re, sys
rows = [r for r in csv.reader(open(sys.argv[2])) if r and not r[0].startswith("#")]
t0 = int(next(csv.DictReader(open(sys.argv[3])))["t_cam_ns"])
truth = [(int(r[0]), 1e3 * float(r[1])) for r in rows]
print("| t [s] | t̂_d + δt [ms] | true t_d [ms] |")
print("|---:|---:|---:|")
md = open(sys.argv[1]).read().split("Time-offset error per time bin")[-1]
for line in md.splitlines():
    m = re.match(r"\| ([\d.]+) \| [-\d.]+ \| [\d.]+ \| [-\d.]+ \| ([-\d.]+) \|", line)
    if m:
        t = t0 + float(m.group(1)) * 1e9
        tt = min(truth, key=lambda x: abs(x[0] - t))[1]
        print(f"| {m.group(1)} | {m.group(2)} | {tt:.2f} |")
PY
