#!/usr/bin/env bash
# Issue #38, "JPEG-compressed: APE within 5 % of the raw run's", decided with a paired design: for each dither seed k
# (write_mcap.mjs --dither k: every pixel -1, 0 or +1 grey level, seeded) the raw arm (mono8 Image) and each JPEG arm
# (jpeg-js at quality Q, CompressedImage) are written from the SAME dithered pixels (write_mcap.mjs dithers, then
# encodes; checked for seed 1 by mcap_jpeg_pairing.mjs: the JPEG file's images are byte for byte the JPEGs of the raw
# file's pixels), replayed by `ovton run` with `--calib` the folder, and scored by `ovton eval` (APE RMSE, posyaw).
# Data: the real moving cut (EuRoC config, --init groundtruth) and the quickstart render (ovton simulate --builtin
# --duration-s 20 --td0-ms 10 --seed 1, sim config, sr). One process at a time, under nice.
# Writes OUT/runs.csv (data,seed,arm,ape_m,wall_s; resumable: rows already there are not run again), OUT/pairing.txt
# and OUT/summary.md (mcap_jpeg_paired_stats.py: means, ratio of the means with a paired bootstrap 95 % interval,
# per-seed ratios).
# Usage: [OVTON_BIN=build/ovton] scripts/experiments/mcap_jpeg_paired_ape.sh [OUT] [K_MOVING] [K_RENDER]
#          [QS_MOVING] [QS_RENDER]
#   defaults: results/mcap_jpeg_paired_ape 80 40 "95 80" "95". The raw arm and the first quality of both data sets
#   run first, then the further qualities (so that a cut-short run has the main rows). Per seed on a shared 2-core
#   machine: moving cut ~12 s (raw + q95), render ~45 s (writing 398 JPEGs with jpeg-js takes ~28 s).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/mcap_jpeg_paired_ape}
K_MOVING=${2:-80}
K_RENDER=${3:-40}
QS_MOVING=${4:-95 80}
QS_RENDER=${5:-95}
SCRATCH=$(mktemp -d /tmp/ovton_jpeg_paired.XXXXXX)
trap 'rm -rf "$SCRATCH"' EXIT
# shellcheck source=scripts/experiments/mcap_experiment_setup.sh
. scripts/experiments/mcap_experiment_setup.sh
mkdir -p "$OUT"
[ -f "$OUT/runs.csv" ] || echo "data,seed,arm,ape_m,wall_s" > "$OUT/runs.csv"
SAMPLE="$SCRATCH/sample"
folder() { # data -> folder (the render made on first use)
  if [ "$1" = moving ]; then echo ../shared/data/euroc_v1_01_moving; return; fi
  [ -d "$SAMPLE" ] || nice -n 10 "$BIN" simulate --builtin --duration-s 20 --td0-ms 10 --seed 1 --out "$SAMPLE" -q \
    >/dev/null
  echo "$SAMPLE"
}
run_args() { # data -> ovton run's arguments
  if [ "$1" = moving ]; then echo "run -q -c config/euroc_mav/estimator_config.yaml --init groundtruth"
  else echo "run -q -c config/sim/estimator_config.yaml --td-mode sr"; fi
}
pairing() { # data, Q: seed 1's JPEG file against its raw file
  local F
  F=$(folder "$1")
  nice -n 10 node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/p.mcap" --images raw --compression none \
    --dither 1 >/dev/null
  rm -rf "$SCRATCH/pj"
  nice -n 10 node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/pj.mcap" --images jpeg --jpeg-quality "$2" \
    --dither 1 --dump-jpeg "$SCRATCH/pj" >/dev/null
  echo "$1, seed 1, q$2: $(nice -n 10 node scripts/experiments/mcap_jpeg_pairing.mjs "$TOOLS" "$F" "$SCRATCH/p.mcap" \
    "$SCRATCH/pj" "$2")" >> "$OUT/pairing.txt"
  rm -rf "$SCRATCH/pj" "$SCRATCH/p.mcap" "$SCRATCH/pj.mcap"
}
arm() { # data, seed, arm (raw or qNN): write, replay, score; appends a row to runs.csv
  local data=$1 k=$2 a=$3 F GT t0 ape
  grep -q "^$data,$k,$a," "$OUT/runs.csv" && return 0
  F=$(folder "$data")
  GT=$F/mav0/state_groundtruth_estimate0/data.csv
  t0=$(date +%s.%N)
  if [ "$a" = raw ]; then
    nice -n 10 node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/d.mcap" --images raw --dither "$k" >/dev/null
  else
    nice -n 10 node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/d.mcap" --images jpeg \
      --jpeg-quality "${a#q}" --dither "$k" >/dev/null
  fi
  # shellcheck disable=SC2046
  nice -n 10 "$BIN" $(run_args "$data") --dataset "$SCRATCH/d.mcap" --calib "$F" -o "$SCRATCH/d.csv" >/dev/null 2>&1
  "$BIN" eval --est "$SCRATCH/d.csv" --gt "$GT" --json "$SCRATCH/e.json" >/dev/null
  ape=$(python3 -c "import json,sys; print('%.8f' % json.load(open(sys.argv[1]))['ape_rmse_m'])" "$SCRATCH/e.json")
  echo "$data,$k,$a,$ape,$(python3 -c "import sys; print('%.1f' % (float(sys.argv[2]) - float(sys.argv[1])))" \
    "$t0" "$(date +%s.%N)")" >> "$OUT/runs.csv"
  rm -f "$SCRATCH/d.mcap" "$SCRATCH/d.csv"
}
read -r -a QM <<< "$QS_MOVING"
read -r -a QR <<< "$QS_RENDER"
: > "$OUT/pairing.txt"
pairing moving "${QM[0]}"
pairing render "${QR[0]}"
# The raw arm and the first quality, then the further ones.
for k in $(seq 1 "$K_MOVING"); do arm moving "$k" raw; arm moving "$k" "q${QM[0]}"; done
for k in $(seq 1 "$K_RENDER"); do arm render "$k" raw; arm render "$k" "q${QR[0]}"; done
for q in "${QM[@]:1}"; do for k in $(seq 1 "$K_MOVING"); do arm moving "$k" "q$q"; done; done
for q in "${QR[@]:1}"; do for k in $(seq 1 "$K_RENDER"); do arm render "$k" "q$q"; done; done
{
  echo "Made by \`scripts/experiments/mcap_jpeg_paired_ape.sh $OUT $K_MOVING $K_RENDER \"$QS_MOVING\"" \
    "\"$QS_RENDER\"\` ($(date -u +%F), script at $(git rev-parse --short HEAD), binary $BIN)."
  echo
  python3 scripts/experiments/mcap_jpeg_paired_stats.py "$OUT/runs.csv"
  echo
  echo "Pairing (mcap_jpeg_pairing.mjs):"
  sed 's/^/- /' "$OUT/pairing.txt"
} > "$OUT/summary.md"
cat "$OUT/summary.md"
