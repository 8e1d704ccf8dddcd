#!/usr/bin/env bash
# Fingerprints of a fixed set of runs, to show that a change leaves the estimator's output byte for byte as it was
# (issue 35: the facade, the options tree and the IMU buffer must not move a single trajectory).
#   scripts/experiments/identical_runs.sh OVTON OUT_DIR [DATA_DIR]
# runs the given `ovton` binary on: the quickstart sample (built-in flight, +10 ms), the real moving EuRoC cut at 0 and
# +40 ms (--init groundtruth and --init auto), two realistic renders (V1_02 at +10 ms, MH_03 with the paper's drift)
# and a feature-level flight, in modes sr and ton (and drift, sir where it says), and writes OUT_DIR/md5.txt: one line
# per trajectory and residual log. Compare two binaries with `diff A/md5.txt B/md5.txt`.
# The data is made once in DATA_DIR (default OUT_DIR/../identical_data) with the binary given; the renders need
# ../shared/data. ~15 min on one core the first time (rendering), ~5 min after.
set -euo pipefail
BIN=$(readlink -f "${1:?usage: identical_runs.sh OVTON OUT_DIR [DATA_DIR]}")
OUT=$(mkdir -p "${2:?usage}" && readlink -f "$2")
DATA=$(mkdir -p "${3:-$OUT/../identical_data}" && readlink -f "${3:-$OUT/../identical_data}")
cd "$(dirname "$0")/../.."
SHARED=../shared/data
GT=$SHARED/euroc_groundtruth
SIM=config/sim/estimator_config.yaml
REAL=config/euroc_mav/estimator_config.yaml

make_data() {
  [ -f "$DATA/qs/mav0/cam0/data.csv" ] ||
    "$BIN" simulate --builtin --duration-s 20 --td0-ms 10 --seed 1 --out "$DATA/qs" -q >/dev/null
  [ -f "$DATA/feat/mav0/cam0/data.csv" ] ||
    "$BIN" simulate --builtin --features-only --agility 1 --duration-s 20 --td-model drift --td0-ms 10 \
      --td-bias-ms-per-s 0.5 --seed 2 --out "$DATA/feat" -q >/dev/null
  [ -d "$SHARED" ] || return 0
  [ -f "$DATA/cut40/mav0/cam0/data.csv" ] ||
    "$BIN" perturb --dataset "$SHARED/euroc_v1_01_moving" --out "$DATA/cut40" --td-model constant --td0-ms 40 \
      >/dev/null
  [ -f "$DATA/v102/mav0/cam0/data.csv" ] ||
    "$BIN" simulate --realism euroc --gt "$GT/V1_02_medium.txt" --start-s 5 --duration-s 30 --td0-ms 10 --seed 1 \
      --out "$DATA/v102" -q >/dev/null
  [ -f "$DATA/mh03/mav0/cam0/data.csv" ] ||
    "$BIN" simulate --realism euroc --gt "$GT/MH_03_medium.txt" --start-s 5 --duration-s 30 --td-model drift \
      --td0-ms 10 --td-bias-ms-per-s 0.1 --td-noise-ms-per-sqrt-s 0.1 --seed 1 --out "$DATA/mh03" -q >/dev/null
}

# one NAME DATASET CONFIG MODE [ARGS...]: a run with a residual log (CONFIG - for the built-in defaults); the
# fingerprints of its trajectory, residual log and calibration log go to md5.txt.
one() {
  local name=$1 ds=$2 cfg=$3 mode=$4
  shift 4
  local t="$OUT/$name.csv" r="$OUT/$name.res.csv" c=()
  [ "$cfg" = - ] || c=(-c "$cfg")
  if "$BIN" run -q "${c[@]}" --dataset "$ds" -m "$mode" -o "$t" --residual-log "$r" "$@" >"$OUT/$name.out" 2>&1; then
    echo "$name $(cat "$t" "$r" "${r%.csv}_calib.csv" | md5sum | cut -c1-32)" >>"$OUT/md5.txt"
  else
    echo "$name failed (exit $?): $(tail -1 "$OUT/$name.out")" >>"$OUT/md5.txt"
  fi
}

make_data
: >"$OUT/md5.txt"
for m in sr ton; do
  one "qs_$m" "$DATA/qs" "$SIM" "$m"
  one "feat_$m" "$DATA/feat" - "$m" --init groundtruth
done
one feat_drift "$DATA/feat" - drift --init groundtruth
one qs_sir_static_search "$DATA/qs" "$SIM" sir --td-init-ms 60
if [ -d "$SHARED" ]; then
  for m in sr ton; do
    one "cut_$m" "$SHARED/euroc_v1_01_moving" "$REAL" "$m" --init groundtruth
    one "cut40_$m" "$DATA/cut40" "$REAL" "$m" --init groundtruth
    one "v102_$m" "$DATA/v102" "$SIM" "$m"
    one "mh03_$m" "$DATA/mh03" "$SIM" "$m"
  done
  one cut_auto_sr "$SHARED/euroc_v1_01_moving" "$REAL" sr --init auto
  one cut40_drift "$DATA/cut40" "$REAL" drift --init groundtruth
  one mh03_drift "$DATA/mh03" "$SIM" drift
fi
# What the coarse search found per run (not fingerprinted: the line carries its wall time).
grep -H "coarse t_d search" "$OUT"/*.out >"$OUT/search.txt" || true
cat "$OUT/md5.txt"
