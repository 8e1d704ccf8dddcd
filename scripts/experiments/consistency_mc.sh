#!/usr/bin/env bash
# Issue #4's consistency over many runs (NEES is a Monte-Carlo statistic; one run's average swings with the seed):
# SEEDS feature-level simulations of a V1_03_difficult stretch (1 px, EuRoC IMU noise, +10 ms), ground-truth
# initialisation, modes oracle and sr. Reports per mode the mean over seeds of the run-average NEES, and the scale
# error of the estimate after a sim(3) fit (mean ± standard error) — the signature of the process-noise bug fixed in
# session 2, which made every trajectory 3–9 % too large.
# Writes OUT/summary.md. Usage: scripts/experiments/consistency_mc.sh [OUT] [SEEDS] [DURATION_S]   (~1 min)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/consistency_mc}
SEEDS=${2:-10}
DUR=${3:-15}
BIN=build/ovton
[ -x "$BIN" ] || scripts/build.sh
source scripts/experiments/run_summary.sh
GT=../shared/data/euroc_groundtruth/V1_03_difficult.txt
if [ ! -f "$GT" ]; then
  echo "consistency_mc.sh needs $GT (../shared/data); skipped" >&2
  exit 0
fi
mkdir -p "$OUT"
{
  echo "# Filter consistency over $SEEDS seeds"
  echo
  echo "Made by \`scripts/experiments/consistency_mc.sh $OUT $SEEDS $DUR\` ($(date -u +%F), commit $(git rev-parse --short HEAD))."
  echo "Data: \`ovton simulate --gt V1_03_difficult.txt --start-s 20 --duration-s $DUR --features-only --seed 1..$SEEDS\`."
  echo
  echo "| mode | NEES orientation | NEES position | APE [m] | scale error (mean ± s.e.) |"
  echo "|---|---|---|---|---|"
} >"$OUT/summary.md"
for M in oracle sr; do
  rows=""
  for S in $(seq 1 "$SEEDS"); do
    DS="$OUT/data_$S"
    [ -d "$DS/mav0" ] || "$BIN" simulate --out "$DS" --gt "$GT" --start-s 20 --duration-s "$DUR" --features-only \
      --td0-ms 10 --seed "$S" -q >/dev/null
    LINE=$("$BIN" run --dataset "$DS" --td-mode "$M" --init groundtruth --output "$OUT/traj_${M}_$S.csv" -q)
    SC=$(scale_error_pct "$BIN" "$OUT/traj_${M}_$S.csv" "$DS/mav0/state_groundtruth_estimate0/data.csv")
    rows="$rows$(nees_ori "$LINE") $(nees_pos "$LINE") $(ape_m "$LINE") $SC"$'\n'
  done
  echo -n "$rows" | awk -v m="$M" '{o+=$1; p+=$2; a+=$3; s+=$4; ss+=$4*$4; n++}
    END {mu=s/n; printf "| %s | %.2f | %.2f | %.3f | %.2f ± %.2f %% |\n", m, o/n, p/n, a/n, mu, sqrt((ss/n-mu*mu)/n)}' \
    >>"$OUT/summary.md"
done
cat "$OUT/summary.md"
