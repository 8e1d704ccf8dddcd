#!/usr/bin/env bash
# Issue #17: memory stays flat while a ROS bag larger than 1 GB is replayed. Renders a short and a long built-in flight
# (clean realism: small PNG folders; the bag stores raw mono8, 361 kB an image), exports both with `ovton export`,
# replays each bag with `ovton run` under /usr/bin/time -v and reports the peak RSS against the bag's size. The
# folders and bags are deleted at the end (the long bag is ~1.2 GB). Writes OUT/summary.md.
# Usage: scripts/experiments/bag_memory.sh [OUT] [LONG_S]   (~15 min on 2 busy cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/bag_memory}
LONG_S=${2:-170}
BIN=$PWD/build/ovton
CFG=config/sim/estimator_config.yaml
SCRATCH=$(mktemp -d /tmp/ovton_bag_memory.XXXXXX)
trap 'rm -rf "$SCRATCH"' EXIT
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
ROWS="$OUT/rows.tsv"
: > "$ROWS"
for S in 20 "$LONG_S"; do
  DS="$SCRATCH/flight_$S"
  nice -n 10 "$BIN" simulate --builtin --realism clean --duration-s "$S" --seed 1 --out "$DS" -q >/dev/null
  nice -n 10 "$BIN" export --dataset "$DS" --bag "$SCRATCH/flight_$S.bag" --no-kalibr -q >/dev/null
  BAG_MB=$(du -m "$SCRATCH/flight_$S.bag" | awk '{print $1}')
  rm -rf "$DS/mav0/cam0/data" # the bag must not find its images anywhere else
  TIME="$SCRATCH/time_$S.txt"
  nice -n 10 /usr/bin/time -v "$BIN" run --dataset "$SCRATCH/flight_$S.bag" --calib "$DS" -c "$CFG" \
    -o "$SCRATCH/traj_$S.csv" -q > "$SCRATCH/run_$S.txt" 2> "$TIME"
  RSS_MB=$(awk -F: '/Maximum resident set size/ {printf "%.0f", $2 / 1024}' "$TIME")
  WALL=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$TIME")
  POSES=$(($(wc -l < "$SCRATCH/traj_$S.csv") - 1))
  printf '%s\t%s\t%s\t%s\t%s\n' "$S" "$BAG_MB" "$POSES" "$RSS_MB" "$WALL" >> "$ROWS"
  rm -rf "$DS" "$SCRATCH/flight_$S.bag"
done
{
  echo "Made by \`scripts/experiments/bag_memory.sh $OUT $LONG_S\` ($(date -u +%F), commit $(git rev-parse --short HEAD));"
  echo "data: \`ovton simulate --builtin --realism clean --duration-s S --seed 1\`, \`ovton export --no-kalibr\`;"
  echo "run: \`ovton run --dataset B.bag --calib FOLDER -c $CFG\` (the folder's images deleted first)."
  echo
  echo "| flight [s] | bag [MB] | poses written | peak RSS [MB] | wall time |"
  echo "|---:|---:|---:|---:|---:|"
  awk -F'\t' '{ printf "| %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5 }' "$ROWS"
} > "$OUT/summary.md"
cat "$OUT/summary.md"
