#!/usr/bin/env bash
# Why max_clones is 20: accuracy and consistency of the MSCKF (mode oracle, no SLAM features) against the window
# length on a feature-level simulation along V1_03_difficult (60 s from 20 s in, 1 px noise, EuRoC IMU noise).
# Usage: scripts/experiments/window_size.sh [OUT]          (needs ../shared/data; ~2 min)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/window_size}
BIN=build/ovton
[ -x "$BIN" ] || scripts/build.sh
source scripts/experiments/run_summary.sh
mkdir -p "$OUT"
DS="$OUT/data_V1_03"
[ -d "$DS/mav0" ] || "$BIN" simulate --out "$DS" --gt ../shared/data/euroc_groundtruth/V1_03_difficult.txt \
  --start-s 20 --duration-s 60 --features-only --td0-ms 10 --seed 1 -q
{
  echo "# Window length (max_clones), mode oracle, feature-level V1_03_difficult"
  echo
  echo "Made by \`scripts/experiments/window_size.sh $OUT\` ($(date -u +%F), commit $(git rev-parse --short HEAD))."
  echo
  echo "| max_clones | NEES orientation | NEES position | APE [m] | update [ms/frame] |"
  echo "|---|---|---|---|---|"
} > "$OUT/summary.md"
for C in 8 11 15 20 30; do
  printf "update:\n  max_clones: %s\n" "$C" > "$OUT/cfg_$C.yaml"
  LINE=$("$BIN" run --dataset "$DS" --config "$OUT/cfg_$C.yaml" --td-mode oracle --init groundtruth \
    --output "$OUT/traj_$C.csv" -q)
  UPD=$(echo "$LINE" | sed -n 's/.*update \([0-9.]*\);.*/\1/p')
  echo "| $C | $(nees_ori "$LINE") | $(nees_pos "$LINE") | $(ape_m "$LINE") | $UPD |" >> "$OUT/summary.md"
done
cat "$OUT/summary.md"
