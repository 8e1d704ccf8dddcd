#!/usr/bin/env bash
# Issue #13's IMU comparison: `sr` on fully synthetic folders (--realism euroc: rendered images and the synthetic IMU
# error model measured on the real V1_01 log) against semi-real ones (the same rendered images, the real V1_01 IMU
# log via --imu-from) - on the real cut's span and on ten more spans of V1_01 - plus the IMU measurement reports.
# All folders follow EuRoC's own ground truth of V1_01 (the moving cut's state_groundtruth_estimate0), whose body
# frame agrees with the IMU's axes (see OUT/imu_match_native.yaml); constant +10 ms offset; `ovton run` with
# config/sim/estimator_config.yaml (ground-truth initialisation). Writes OUT/summary.md.
# Usage: scripts/experiments/imu_realism.sh [OUT] [SEEDS]     (needs ../shared/data; ~25 min on one busy core)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/imu_realism}
SEEDS=${2:-10}
DATA=../shared/data
CUT=$DATA/euroc_v1_01_moving
GT=$CUT/mav0/state_groundtruth_estimate0/data.csv
BIN=${OVTON_BIN:-build/ovton} # OVTON_BIN: a copy of the binary, to go on building while it runs
[ -x "$BIN" ] || scripts/build.sh
. scripts/experiments/run_summary.sh
mkdir -p "$OUT"

"$BIN" simulate --match-imu --gt "$GT" --imu-from "$CUT" > "$OUT/imu_match_native.yaml"
"$BIN" simulate --match-imu --gt "$DATA/euroc_groundtruth/V1_01_easy.txt" --imu-from "$CUT" > "$OUT/imu_match_txt.yaml"
"$BIN" simulate --match-imu --gt "$DATA/euroc_groundtruth/V1_01_easy.txt" --imu-from "$CUT" --knot-dt-s 0.03 \
  > "$OUT/imu_match_txt_knots003.yaml"

# run KIND REALISM SEED START -> "ape are" ; KIND syn | semi
run() {
  local kind=$1 realism=$2 seed=$3 start=$4 extra=""
  [ "$kind" = semi ] && extra="--imu-from $CUT"
  local d="$OUT/work_${kind}_${realism}_${seed}_${start}"
  [ -d "$d/mav0" ] || nice -n 10 "$BIN" simulate --realism "$realism" --gt "$GT" --start-s "$start" --duration-s 4.62 \
    --seed "$seed" $extra --out "$d" -q >/dev/null
  local line
  line=$(nice -n 10 "$BIN" run -d "$d" -c config/sim/estimator_config.yaml -o "$d.csv" -q)
  echo "$(ape_m "$line") $(echo "$line" | sed -n 's/.*ARE \([0-9.]*\) deg.*/\1/p')"
  rm -rf "$d"
}

: > "$OUT/runs.txt"
# The real cut's span: its first image is 12.0 s after the ground truth's first pose; images start 0.1 s in.
# The same scenes (seeds) for both IMUs, so that the ratio compares IMUs and not rooms.
for s in $(seq 1 "$SEEDS"); do
  echo "span syn euroc $s $(run syn euroc "$s" 11.9)" >> "$OUT/runs.txt"
  echo "span semi euroc $s $(run semi euroc "$s" 11.9)" >> "$OUT/runs.txt"
done
for s in 1 2 3; do echo "span syn clean $s $(run syn clean "$s" 11.9)" >> "$OUT/runs.txt"; done
for st in 15 27 39 51 63 75 87 99 111 123; do
  echo "spans syn euroc $st $(run syn euroc "$st" "$st")" >> "$OUT/runs.txt"
  echo "spans semi euroc $st $(run semi euroc "$st" "$st")" >> "$OUT/runs.txt"
done

python3 - "$OUT" "$SEEDS" "$(git rev-parse --short HEAD)" > "$OUT/summary.md" <<'PY'
import sys, collections
out, seeds, commit = sys.argv[1], sys.argv[2], sys.argv[3]
runs = collections.defaultdict(list)
for line in open(f"{out}/runs.txt"):
    where, kind, realism, seed, ape, are = line.split()
    runs[(where, kind, realism)].append((float(ape), float(are)))
def cell(v, i, scale, dec):
    x = [r[i] * scale for r in v]
    return f"{sum(x) / len(x):.{dec}f} ({min(x):.{dec}f}–{max(x):.{dec}f})"
print("# Synthetic vs real IMU under `sr` (issue 13)\n")
print(f"Made by `scripts/experiments/imu_realism.sh {out} {seeds}` (commit {commit}). Mean (min–max) over runs.\n")
print("| where | images | IMU | runs | APE [mm] | ARE [deg] |\n|---|---|---|---|---|---|")
names = {'syn': 'synthetic (error model)', 'semi': 'real V1_01 log'}
for (where, kind, realism), v in sorted(runs.items()):
    span = 'real cut span (1 span, scenes vary)' if where == 'span' else '10 spans of V1_01, 4.5 s each'
    imu = names[kind] if realism == 'euroc' else 'synthetic (datasheet only, clean)'
    print(f"| {span} | {realism} | {imu} | {len(v)} | {cell(v, 0, 1000, 1)} | {cell(v, 1, 1, 2)} |")
syn = runs[('span', 'syn', 'euroc')]; semi = runs[('span', 'semi', 'euroc')]
m = lambda v: sum(r[0] for r in v) / len(v)
print(f"\nOn the real cut's span: semi-real / synthetic APE = {m(semi) / m(syn):.2f} (criterion: within 1.5).")
syn = runs[('spans', 'syn', 'euroc')]; semi = runs[('spans', 'semi', 'euroc')]
print(f"Over ten spans: semi-real / synthetic APE = {m(semi) / m(syn):.2f}.")
PY
cat "$OUT/summary.md"
