#!/usr/bin/env bash
# The paper's experiment designs on our data (issue #5):
#  Table III: 7 EuRoC trajectories (MH_03, MH_04, MH_05, V1_02, V1_03, V2_02, V2_03) x drift noise 0.1 and
#             0.125 ms/sqrt(s) (cumulative bias 0.1 ms/s, start 10 ms), modes sr / sir / ton (the paper's OV_SR,
#             OV_SIR, OV_TON) plus off and oracle for reference; TPE [mm] and APE [m] in the paper's layout.
#  Table II:  constant offsets -20, -10, +10, +20 ms on V1_03_difficult and MH_03_medium, modes sir / ton / sr:
#             CIT [frames] and APE [m].
# Usage: scripts/experiments/protocol.sh [OUT] [--quick]
#   default: rendered images (real KLT front end), 60 s per folder        (~2-3 h on 2 cores)
#   --quick: feature-level folders with 0.3 px noise (KLT-like), 30 s     (~15 min)
# Needs ../shared/data. Writes OUT/table3.md, OUT/table2.md and one `ovton compare` folder per case.
# PROTOCOL_CONFIG=FILE runs every case with that estimator config instead of config/sim/estimator_config.yaml
# (e.g. one with `sir_first_velocity: next`); the tables name it.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/protocol}
QUICK=0
[ "${2:-}" = "--quick" ] && QUICK=1
BIN=build/ovton
[ -x "$BIN" ] || scripts/build.sh
GT=../shared/data/euroc_groundtruth
mkdir -p "$OUT"
CFG=${PROTOCOL_CONFIG:-config/sim/estimator_config.yaml}
if [ $QUICK = 1 ]; then SIMARGS=(--features-only --pixel-noise 0.3 --duration-s 30)
else SIMARGS=(--duration-s 60); fi

run_case() { # name, compare modes, simulate args...
  local name=$1 modes=$2; shift 2
  local ds="$OUT/data_$name"
  [ -d "$ds/mav0" ] || "$BIN" simulate --out "$ds" "${SIMARGS[@]}" "$@" -q >/dev/null
  [ -f "$OUT/$name/results.csv" ] || "$BIN" compare --dataset "$ds" --modes "$modes" --out "$OUT/$name" \
    --config "$CFG" --jobs 2 >/dev/null 2>&1 || true
  echo "done $name" >&2
}

SEQS="MH_03_medium MH_04_difficult MH_05_difficult V1_02_medium V1_03_difficult V2_02_medium V2_03_difficult"
for N in 0.1 0.125; do
  for S in $SEQS; do
    run_case "t3_${S}_n$N" off,sr,sir,ton,oracle --gt "$GT/$S.txt" --start-s 20 --td-model drift --td0-ms 10 \
      --td-bias-ms-per-s 0.1 --td-noise-ms-per-sqrt-s "$N" --seed 1
  done
done
for S in V1_03_difficult MH_03_medium; do
  for TD in -20 -10 10 20; do
    run_case "t2_${S}_td$TD" sr,sir,ton --gt "$GT/$S.txt" --start-s 20 --td-model constant --td0-ms "$TD" --seed 1
  done
done
python3 scripts/experiments/protocol_tables.py "$OUT" "$QUICK" "$(git rev-parse --short HEAD)"
cat "$OUT/table3.md" "$OUT/table2.md"
