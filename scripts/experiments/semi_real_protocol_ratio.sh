#!/usr/bin/env bash
# Issue #37: how much harder is the real IMU than the synthetic error model on the semi-real protocol's folders?
# Per sequence, span and scene (seed), two folders with the same images (--realism euroc, +10 ms constant, rendered
# along EuRoC's own estimate <seq>.csv — MH_03: <seq>.txt — with the workflow's knots), `sr` with ground-truth
# initialisation and config/sim on each:
#   syn    the synthetic IMU (the error model measured on V1_01's real log)
#   semi   the sequence's real imu0 log (../shared/data/euroc_imu0, `--imu-from FILE`), as `imu_source: real` does
# The semi folder takes the syn folder's images (hard links): `--imu-from` changes only imu0/, the ground truth and
# sim.yaml. Reports APE per kind and the semi / syn ratios (ratio of means; paired: geometric mean over scenes), per
# sequence and over all, as docs/simulate.md's table of V1_01 does.
#
# Usage (runs in the repo root):
#   [SEQS="MH_03_medium ..."] [STARTS="40"] [DUR=4.62] [KNOT=0.03] [OVTON_BIN=build/ovton] \
#     scripts/experiments/semi_real_protocol_ratio.sh [OUT] [SEEDS]
#   OUT default results/semi_real_protocol_ratio (rendered folders in OUT/work are reused; OUT/runs.txt rewritten)
#   SEEDS N: scenes 1..N (default 3). STARTS: span starts [s after the ground truth's first pose].
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
cd "$HERE/../.."
OUT=${1:-results/semi_real_protocol_ratio}
SEEDS=${2:-3}
SEQS=${SEQS:-MH_03_medium MH_04_difficult MH_05_difficult V1_02_medium V1_03_difficult V2_02_medium V2_03_difficult}
STARTS=${STARTS:-40}
DUR=${DUR:-4.62}
KNOT=${KNOT:-0.03}
DATA=../shared/data
BIN=${OVTON_BIN:-build/ovton}
NICE="nice -n 10"
mkdir -p "$OUT/work"
: > "$OUT/runs.txt"

score() { # KIND SEQ START SEED FOLDER -> appends "KIND SEQ START SEED APE_m ARE_deg" ("fail fail" if no result)
  local res=""
  if $NICE "$BIN" run -d "$5" -c config/sim/estimator_config.yaml --init groundtruth -o "$5.csv" -q --no-prefetch \
    > "$5.log" 2>&1 &&
    $NICE "$BIN" eval --est "$5.csv" --gt "$5/mav0/state_groundtruth_estimate0/data.csv" --align posyaw \
      --json "$5.json" > /dev/null 2>> "$5.log"; then
    res=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['ape_rmse_m'], j['are_rmse_deg'])" "$5.json")
  fi
  echo "$1 $2 $3 $4 ${res:-fail fail}" >> "$OUT/runs.txt"
}

for SEQ in $SEQS; do
  GT=$DATA/euroc_groundtruth/$SEQ.csv
  [ -f "$GT" ] || GT=$DATA/euroc_groundtruth/$SEQ.txt
  LOG=$DATA/euroc_imu0/$(echo "$SEQ" | cut -d_ -f1)$(echo "$SEQ" | cut -d_ -f2).csv
  for START in $STARTS; do
    for s in $(seq 1 "$SEEDS"); do
      args=(--realism euroc --gt "$GT" --knot-dt-s "$KNOT" --start-s "$START" --duration-s "$DUR" --seed "$s"
        --td-model constant --td0-ms 10)
      syn="$OUT/work/syn_${SEQ}_${START}_$s" semi="$OUT/work/semi_${SEQ}_${START}_$s"
      if [ ! -d "$syn/mav0" ]; then
        rm -rf "$syn.tmp"
        $NICE "$BIN" simulate "${args[@]}" --out "$syn.tmp" -q > /dev/null
        mv "$syn.tmp" "$syn"
      fi
      if [ ! -d "$semi/mav0" ]; then
        rm -rf "$semi.imu" "$semi.tmp"
        $NICE "$BIN" simulate "${args[@]}" --imu-from "$LOG" --no-images --out "$semi.imu" -q > /dev/null
        cmp -s "$syn/mav0/cam0/data.csv" "$semi.imu/mav0/cam0/data.csv" || { echo "image stamps differ: $semi" >&2; exit 1; }
        cp -al "$syn" "$semi.tmp"
        for f in mav0/imu0/data.csv mav0/imu0/sensor.yaml mav0/state_groundtruth_estimate0/data.csv sim.yaml; do
          rm "$semi.tmp/$f"
          cp "$semi.imu/$f" "$semi.tmp/$f"
        done
        rm -rf "$semi.imu"
        mv "$semi.tmp" "$semi"
      fi
      score syn "$SEQ" "$START" "$s" "$syn"
      score semi "$SEQ" "$START" "$s" "$semi"
    done
  done
  echo "$SEQ: $(awk -v q="$SEQ" '$2 == q' "$OUT/runs.txt" | wc -l) runs" >&2
done

python3 - "$OUT" << 'PY' | tee "$OUT/summary.md"
import math, sys
from collections import defaultdict
ape, fails = defaultdict(dict), defaultdict(int)
for line in open(sys.argv[1] + "/runs.txt"):
    kind, seq, start, seed, a, _ = line.split()
    if a == "fail":
        fails[(kind, seq)] += 1
    else:
        ape[kind][(seq, start, seed)] = float(a)
print("| sequence | syn APE [mm] | semi APE [mm] | semi / syn (ratio of means) | paired (geometric mean) | scenes | failed runs (syn, semi) |")
print("|---|---:|---:|---:|---:|---:|---|")
seqs = sorted({k[0] for k in ape["syn"]} | {k[0] for k in ape["semi"]} | {q for _, q in fails})
for name, sel in [(q, [q]) for q in seqs] + [("all", seqs)]:
    keys = sorted(k for k in set(ape["syn"]) & set(ape["semi"]) if k[0] in sel)
    f = f"{sum(fails[('syn', q)] for q in sel)}, {sum(fails[('semi', q)] for q in sel)}"
    if not keys:
        print(f"| {name} | – | – | – | – | 0 | {f} |")
        continue
    ms = sum(ape["syn"][k] for k in keys) / len(keys)
    mm = sum(ape["semi"][k] for k in keys) / len(keys)
    paired = math.exp(sum(math.log(ape["semi"][k] / ape["syn"][k]) for k in keys) / len(keys))
    print(f"| {name} | {1e3 * ms:.1f} | {1e3 * mm:.1f} | {mm / ms:.2f} | {paired:.2f} | {len(keys)} | {f} |")
PY
