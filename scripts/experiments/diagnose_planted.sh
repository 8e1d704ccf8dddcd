#!/usr/bin/env bash
# Planted effects through the filter, over seeds: what `ovton diagnose` names first and its size.
# For every seed: a 20 s feature-level simulation of the built-in flight (1 px noise, t_d 10 ms) with one planted
# effect, `ovton run --td-mode off` (t_d held at the true mean offset) with a residual log, `ovton diagnose --dataset`.
#   readout  25 ms rolling shutter, --agility 1 (a readout shows in the rates only through angular acceleration)
#   focal    data made with focal lengths 1 % larger than cam0/sensor.yaml says
#   gyro_scale  the gyro reads 1 % more than the true rate, --agility 1 (the rate must vary within the bias's bins)
#   clean    nothing planted (the plain flight)
#   clean_agile nothing planted, --agility 1
# Prints one line per case and seed (the top three candidates) and writes OUT/planted.txt.
# Usage: scripts/experiments/diagnose_planted.sh [OUT] [SEEDS...]   (default seeds 1 2 3 4; ~15 s per case and seed)
#   OVTON_BIN overrides the binary.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/diagnose_planted}
shift || true
SEEDS=("$@")
[ ${#SEEDS[@]} -gt 0 ] || SEEDS=(1 2 3 4)
BIN=${OVTON_BIN:-build/ovton}
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
: >"$OUT/planted.txt"
one() { # name seed td_init_ms sim-args...
  local name=$1 seed=$2 td=$3
  shift 3
  local dir="$OUT/${name}_seed$seed"
  "$BIN" simulate --out "$dir" --builtin --duration-s 20 --seed "$seed" --features-only --td-model constant \
    --td0-ms 10 "$@" --force -q >/dev/null
  "$BIN" run --dataset "$dir" --td-mode off --init groundtruth --td-init-ms "$td" --output "$dir/run.csv" \
    --residual-log "$dir/res.csv" -q >/dev/null
  "$BIN" diagnose --log "$dir/res.csv" --dataset "$dir" --out "$dir/diagnose" | grep -E '^[123] ' |
    sed "s/^/$name seed $seed: /" | tee -a "$OUT/planted.txt"
}
for s in "${SEEDS[@]}"; do
  one readout "$s" 22.5 --readout-ms 25 --agility 1 # the filter holds the mid-row offset: 10 + 25/2 ms
  one focal "$s" 10 --focal-error-pct 1
  one gyro_scale "$s" 10 --gyro-scale-pct 1 --agility 1
  one clean "$s" 10
  one clean_agile "$s" 10 --agility 1
done
