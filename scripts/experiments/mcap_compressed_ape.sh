#!/usr/bin/env bash
# Issue #38: recordings written by writers that are not ovton's (scripts/mcap_tools: @mcap/core from npm, a Python
# standard-library rosbag2 SQLite writer) replay to the folder's trajectory, raw and JPEG-compressed. For the real
# moving cut and a render (the quickstart sample):
#   - raw images in an MCAP file (@mcap/core) and in a .db3 bag (Python): byte-identical trajectory to the folder's?
#   - JPEG (jpeg-js, quality Q) in both: the APE against the raw run's;
#   - how far the APE moves with any change of the pixels: K runs each of raw and JPEG images dithered by +-1 grey
#     level (seeded, write_mcap.mjs --dither), their mean and spread.
# Writes OUT/summary.md. Needs node with scripts/mcap_tools' npm packages (npm ci --prefix scripts/mcap_tools),
# python3 and ../shared/data. Usage: [OVTON_BIN=build/ovton] scripts/experiments/mcap_compressed_ape.sh [OUT] [K] [Q]
# (~25 min, 2 busy cores). The paired version with enough seeds to decide the 5 % bar: mcap_jpeg_paired_ape.sh.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/mcap_compressed_ape}
K=${2:-6}
Q=${3:-95}
SCRATCH=$(mktemp -d /tmp/ovton_mcap_ape.XXXXXX)
trap 'rm -rf "$SCRATCH"' EXIT
# shellcheck source=scripts/experiments/mcap_experiment_setup.sh
. scripts/experiments/mcap_experiment_setup.sh
mkdir -p "$OUT"
SAMPLE="$SCRATCH/sample"
nice -n 10 "$BIN" simulate --builtin --duration-s 20 --td0-ms 10 --seed 1 --out "$SAMPLE" -q >/dev/null
ape() { # trajectory, ground truth -> APE RMSE [m]
  "$BIN" eval --est "$1" --gt "$2" --json "$SCRATCH/e.json" >/dev/null
  python3 -c "import json,sys; print('%.5f' % json.load(open(sys.argv[1]))['ape_rmse_m'])" "$SCRATCH/e.json"
}
stats() { # numbers -> "mean +- sd"
  python3 -c "import statistics as s,sys; v=[float(x) for x in sys.argv[1:]]; print('%.5f +- %.5f' % (s.mean(v), s.stdev(v)))" "$@"
}
{
  echo "Made by \`scripts/experiments/mcap_compressed_ape.sh $OUT $K $Q\` ($(date -u +%F), commit $(git rev-parse --short HEAD))."
  echo "Writers: \`node scripts/mcap_tools/write_mcap.mjs\` (@mcap/core $(node -p "require('$TOOLS/node_modules/@mcap/core/package.json').version"), CDR by @foxglove/rosmsg2-serialization, JPEG by jpeg-js, quality $Q)"
  echo "and \`python3 scripts/mcap_tools/write_db3.py\` (rosbag2 sqlite3); replayed with \`--calib\` the folder."
  echo
  echo "| data | run | folder APE [m] | raw MCAP | raw .db3 | JPEG MCAP APE [m] | JPEG .db3 APE [m] | JPEG / raw | dithered raw APE (K=$K) | dithered JPEG APE (K=$K) |"
  echo "|---|---|---:|---|---|---:|---:|---:|---:|---:|"
} > "$OUT/summary.md"
: > "$OUT/values.txt"
for data in moving render; do
  if [ $data = moving ]; then
    F=../shared/data/euroc_v1_01_moving
    RUN=(run -q -c config/euroc_mav/estimator_config.yaml --init groundtruth)
  else
    F=$SAMPLE
    RUN=(run -q -c config/sim/estimator_config.yaml --td-mode sr)
  fi
  GT=$F/mav0/state_groundtruth_estimate0/data.csv
  nice -n 10 "$BIN" "${RUN[@]}" --dataset "$F" -o "$SCRATCH/folder.csv" 2>/dev/null
  A_F=$(ape "$SCRATCH/folder.csv" "$GT")
  same() { cmp -s "$1" "$SCRATCH/folder.csv" && echo "byte-identical" || echo "DIFFERS"; }
  node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/raw.mcap" >/dev/null
  python3 "$TOOLS/write_db3.py" --folder "$F" --out "$SCRATCH/rawbag" >/dev/null
  nice -n 10 "$BIN" "${RUN[@]}" --dataset "$SCRATCH/raw.mcap" --calib "$F" -o "$SCRATCH/r1.csv" 2>/dev/null
  nice -n 10 "$BIN" "${RUN[@]}" --dataset "$SCRATCH/rawbag" --calib "$F" -o "$SCRATCH/r2.csv" 2>/dev/null
  S1=$(same "$SCRATCH/r1.csv")
  S2=$(same "$SCRATCH/r2.csv")
  node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/jpg.mcap" --images jpeg --jpeg-quality "$Q" \
    --dump-jpeg "$SCRATCH/jpg" >/dev/null
  python3 "$TOOLS/write_db3.py" --folder "$F" --out "$SCRATCH/jpgbag" --images jpeg --jpeg-from "$SCRATCH/jpg" >/dev/null
  nice -n 10 "$BIN" "${RUN[@]}" --dataset "$SCRATCH/jpg.mcap" --calib "$F" -o "$SCRATCH/j1.csv" 2>/dev/null
  nice -n 10 "$BIN" "${RUN[@]}" --dataset "$SCRATCH/jpgbag" --calib "$F" -o "$SCRATCH/j2.csv" 2>/dev/null
  A_J1=$(ape "$SCRATCH/j1.csv" "$GT")
  A_J2=$(ape "$SCRATCH/j2.csv" "$GT")
  RAW=() JPG=()
  for k in $(seq 1 "$K"); do
    for kind in raw jpeg; do
      node "$TOOLS/write_mcap.mjs" --folder "$F" --out "$SCRATCH/d.mcap" --images $kind --jpeg-quality "$Q" \
        --dither "$k" >/dev/null
      nice -n 10 "$BIN" "${RUN[@]}" --dataset "$SCRATCH/d.mcap" --calib "$F" -o "$SCRATCH/d.csv" 2>/dev/null
      if [ $kind = raw ]; then RAW+=("$(ape "$SCRATCH/d.csv" "$GT")"); else JPG+=("$(ape "$SCRATCH/d.csv" "$GT")"); fi
    done
  done
  echo "| $data | \`${RUN[*]}\` | $A_F | $S1 | $S2 | $A_J1 | $A_J2 | $(python3 -c "print('%.3f' % ($A_J1 / $A_F))") | $(stats "${RAW[@]}") | $(stats "${JPG[@]}") |" >> "$OUT/summary.md"
  echo "$data dithered raw: ${RAW[*]}; dithered JPEG: ${JPG[*]}" >> "$OUT/values.txt"
  rm -rf "$SCRATCH/rawbag" "$SCRATCH/jpgbag" "$SCRATCH/jpg"
done
cat "$OUT/summary.md" "$OUT/values.txt"
