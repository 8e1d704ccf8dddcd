#!/usr/bin/env bash
# Issue #13: is a fully synthetic folder as hard for `sr` as a semi-real one (the real V1_01 IMU log) once the
# semi-real images follow the motion the real IMU saw? Per scene (seed) and span, four folders of --realism euroc,
# +10 ms, ground-truth initialisation, config/sim/estimator_config.yaml:
#   syn_coarse   images and synthetic IMU along the spline of EuRoC's 20 Hz state_groundtruth_estimate0 (knots 0.1 s)
#   semi_coarse  the same images, the real IMU log (`--imu-from`): the construction measured before (images miss
#                the 1.5-20 Hz motion the IMU recorded; scripts/experiments/imu_surrogate.sh)
#   syn_fine     images and synthetic IMU along EuRoC's 200 Hz pose file moved onto the real IMU
#                (`--gt V1_01_easy.txt --knot-dt-s 0.03 --align-gt <cut>`: clock, axes, gravity, lever arm)
#   semi_fine    the same images, the real IMU log
# and reports APE per kind and the semi / syn ratios (ratio of means, and paired: geometric mean over scenes).
# The semi folders take their images from the syn folder of the same scene (hard links): `--imu-from` changes only
# imu0/, the ground truth and sim.yaml (the images depend on the trajectory and seed alone).
#
# Usage (from anywhere; runs in the repo root):
#   [SPANS="s1 s2 ..."] [OVTON_BIN=build/ovton] scripts/experiments/semi_real_fine.sh [OUT] [SEEDS]
#   OUT    default results/semi_real_fine; rendered folders in OUT/work are reused, OUT/runs.txt is rewritten
#   SEEDS  N: scenes 1..N on every span (default 10)
#   SPANS  span starts [s after the 20 Hz ground truth's first pose], 4.62 s each; default 11.9 (the real moving
#          cut's span, images 1403715285.26-289.71 s); SPANS=ten: 15 27 39 ... 123 (imu_realism.sh's spans)
#   BLEND  --align-blend-hz of the fine reference (default 1.5); KINDS="coarse fine" (default) or one of them
# Needs ../shared/data (euroc_v1_01_moving and euroc_groundtruth/V1_01_easy.txt). ~25 s per scene on 2 cores.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
cd "$HERE/../.."
OUT=${1:-results/semi_real_fine}
SEEDS=${2:-10}
SPANS=${SPANS:-11.9}
[ "$SPANS" = ten ] && SPANS="15 27 39 51 63 75 87 99 111 123"
DATA=../shared/data
CUT=$DATA/euroc_v1_01_moving
GT=$CUT/mav0/state_groundtruth_estimate0/data.csv
TXT=$DATA/euroc_groundtruth/V1_01_easy.txt
[ -d "$CUT/mav0" ] && [ -f "$TXT" ] || { echo "semi_real_fine.sh: needs $CUT and $TXT" >&2; exit 2; }
BIN=${OVTON_BIN:-build/ovton}
[ -x "$BIN" ] || scripts/build.sh
DUR=4.62
BLEND=${BLEND:-1.5}
KINDS=${KINDS:-coarse fine}
NICE="nice -n 10"
mkdir -p "$OUT/work"
: > "$OUT/runs.txt"
# The pose file starts at another instant than the 20 Hz ground truth: the same span is START + (first pose of the
# 20 Hz file - first pose of the pose file) after the pose file's start (`--start-s` counts from a file's first pose).
LEAD=$(python3 - "$GT" "$TXT" << 'PY'
import sys
def first(path, scale):
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                return float(line.replace(",", " ").split()[0]) * scale
print("%.6f" % (first(sys.argv[1], 1e-9) - first(sys.argv[2], 1.0)))
PY
)

score() { # KIND SPAN SEED FOLDER -> appends "KIND SPAN SEED APE_m ARE_deg" to runs.txt ("fail fail" if no result)
  local res=""
  if $NICE "$BIN" run -d "$4" -c config/sim/estimator_config.yaml --init groundtruth -o "$4.csv" -q > "$4.log" 2>&1 &&
    $NICE "$BIN" eval --est "$4.csv" --gt "$4/mav0/state_groundtruth_estimate0/data.csv" --align posyaw \
      --json "$4.json" > /dev/null 2>> "$4.log"; then
    res=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['ape_rmse_m'], j['are_rmse_deg'])" "$4.json")
  fi
  echo "$1 $2 $3 ${res:-fail fail}" >> "$OUT/runs.txt"
}

semi_from() { # SYN_FOLDER SEMI_FOLDER SIMULATE_ARGS... : the real IMU under the syn folder's images
  local syn=$1 d=$2
  shift 2
  [ -d "$d/mav0" ] && return
  # Built beside and moved into place whole: an interrupted run leaves no half-made folder to be reused.
  rm -rf "$d.imu" "$d.tmp"
  $NICE "$BIN" simulate "$@" --imu-from "$CUT" --no-images --out "$d.imu" -q > /dev/null
  cmp -s "$syn/mav0/cam0/data.csv" "$d.imu/mav0/cam0/data.csv" || { echo "image stamps differ: $d" >&2; exit 1; }
  cp -al "$syn" "$d.tmp"
  for f in mav0/imu0/data.csv mav0/imu0/sensor.yaml mav0/state_groundtruth_estimate0/data.csv sim.yaml; do
    rm "$d.tmp/$f"
    cp "$d.imu/$f" "$d.tmp/$f"
  done
  rm -rf "$d.imu"
  mv "$d.tmp" "$d"
}

for START in $SPANS; do
  FSTART=$(python3 -c "print('%.6f' % ($START + $LEAD))")
  for s in $(seq 1 "$SEEDS"); do
    for kind in $KINDS; do
      if [ $kind = coarse ]; then
        args=(--realism euroc --gt "$GT" --start-s "$START" --duration-s "$DUR" --seed "$s")
      else
        args=(--realism euroc --gt "$TXT" --knot-dt-s 0.03 --align-gt "$CUT" --align-blend-hz "$BLEND"
          --start-s "$FSTART" --duration-s "$DUR" --seed "$s")
      fi
      syn="$OUT/work/syn_${kind}_${START}_$s"
      if [ ! -d "$syn/mav0" ]; then
        rm -rf "$syn.tmp"
        $NICE "$BIN" simulate "${args[@]}" --out "$syn.tmp" -q > /dev/null
        mv "$syn.tmp" "$syn"
      fi
      semi_from "$syn" "$OUT/work/semi_${kind}_${START}_$s" "${args[@]}"
      score "syn_$kind" "$START" "$s" "$syn"
      score "semi_$kind" "$START" "$s" "$OUT/work/semi_${kind}_${START}_$s"
    done
  done
  echo "span $START: $(awk -v s="$START" '$2 == s' "$OUT/runs.txt" | wc -l) runs" >&2
done

python3 - "$OUT" << 'PY' | tee "$OUT/summary.md"
import math, sys
from collections import defaultdict
out = sys.argv[1]
ape = defaultdict(dict)
fails = defaultdict(int)
for line in open(out + "/runs.txt"):
    kind, span, seed, a, _ = line.split()
    if a == "fail":
        fails[kind] += 1
    else:
        ape[kind][(span, seed)] = float(a)
print("| reference | syn APE [mm] | semi APE [mm] | semi / syn (ratio of means) | paired (geometric mean) | scenes | failed runs |")
print("|---|---:|---:|---:|---:|---:|---|")
for ref in ("coarse", "fine"):
    s, m = ape["syn_" + ref], ape["semi_" + ref]
    keys = sorted(set(s) & set(m))
    if not keys:
        continue
    ms = sum(s[k] for k in keys) / len(keys)
    mm = sum(m[k] for k in keys) / len(keys)
    paired = math.exp(sum(math.log(m[k] / s[k]) for k in keys) / len(keys))
    name = {"coarse": "20 Hz estimate, knots 0.1 s", "fine": "200 Hz pose file aligned to the IMU, knots 0.03 s"}[ref]
    print(f"| {name} | {1e3 * ms:.1f} | {1e3 * mm:.1f} | {mm / ms:.2f} | {paired:.2f} | {len(keys)} | "
          f"syn {fails['syn_' + ref]}, semi {fails['semi_' + ref]} |")
PY
