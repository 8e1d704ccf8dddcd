#!/usr/bin/env bash
# Issue #13: `sr` on --realism euroc renderings along all 11 EuRoC ground truths, 60 s each from 5 s in, with a
# constant true offset of +10 ms; `ovton run --config config/sim/estimator_config.yaml` (ground-truth
# initialisation). Writes OUT/summary.md (APE/ARE, final offset, render cost per sequence); folders are deleted after
# each run (keep them with KEEP=1).
# Usage: scripts/experiments/euroc_all.sh [OUT] [DURATION_S]     (needs ../shared/data; ~1.5 h on one busy core)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/euroc_all}
DUR=${2:-60}
GT=../shared/data/euroc_groundtruth
BIN=build/ovton
[ -x "$BIN" ] || scripts/build.sh
. scripts/experiments/run_summary.sh
mkdir -p "$OUT"
{
  echo "# \`sr\` on euroc renderings of all EuRoC trajectories"
  echo
  echo "Made by \`scripts/experiments/euroc_all.sh $OUT $DUR\` (commit $(git rev-parse --short HEAD)). Each folder:"
  echo "\`ovton simulate --realism euroc --gt $GT/<SEQ>.txt --start-s 5 --duration-s $DUR --td0-ms 10 --seed 1\`;"
  echo "each run: \`ovton run --config config/sim/estimator_config.yaml\` (mode sr, ground-truth initialisation)."
  echo
  echo "| sequence | APE [m] | ARE [deg] | final t̂_d [ms] | t_d σ [ms] | gyro p95 [rad/s] | blur renderings/frame | mean exposure [ms] |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$OUT/summary.md"
for f in "$GT"/*.txt; do
  SEQ=$(basename "$f" .txt)
  DS="$OUT/data_$SEQ"
  [ -d "$DS/mav0" ] || nice -n 10 "$BIN" simulate --realism euroc --gt "$f" --start-s 5 --duration-s "$DUR" \
    --td0-ms 10 --seed 1 --out "$DS" -q >/dev/null
  LINE=$(nice -n 10 "$BIN" run -d "$DS" -c config/sim/estimator_config.yaml -o "$OUT/$SEQ.csv" -q 2>&1 || true)
  echo "$LINE" > "$OUT/$SEQ.log"
  python3 - "$DS" "$SEQ" "$(ape_m "$LINE")" "$(echo "$LINE" | sed -n 's/.*ARE \([0-9.]*\) deg.*/\1/p')" \
    "$(final_td_ms "$LINE")" "$(echo "$LINE" | sed -n 's/.*(sigma \([0-9.]*\) ms).*/\1/p')" >> "$OUT/summary.md" <<'PY'
import math, sys
ds, seq, ape, are, td, sig = sys.argv[1:]
w = []
for line in open(f"{ds}/mav0/imu0/data.csv"):
    if not line.startswith('#'):
        w.append(math.sqrt(sum(float(x) ** 2 for x in line.split(',')[1:4])))
w.sort()
rows = [l.split(',') for l in open(f"{ds}/mav0/cam0/exposure.csv") if not l.startswith('#')]
blur = sum(int(r[3]) for r in rows) / len(rows)
expo = 1e3 * sum(float(r[1]) for r in rows) / len(rows)
print(f"| {seq} | {ape or 'failed'} | {are} | {td} | {sig} | {w[int(0.95 * (len(w) - 1))]:.2f} | {blur:.1f} | {expo:.1f} |")
PY
  [ "${KEEP:-0}" = 1 ] || rm -rf "$DS"
done
cat "$OUT/summary.md"
