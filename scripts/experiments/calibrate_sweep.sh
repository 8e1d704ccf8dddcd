#!/usr/bin/env bash
# Issue 37's bar for `ovton calibrate` swept over the planted range (docs/calibrate.md, "Swept over the planted range").
# Per case: a 12-s render of the built-in flight (--agility 1, euroc realism, seed 1) with a planted camera-IMU
# rotation, focal error, offset and readout against a declared 640x480 pinhole f 480 (no distortion); the sensor
# yamls removed (as tests/test_calibrate.cpp does); `ovton calibrate --out CAL`; the ground truth linked into CAL;
# `ovton run -d CAL -c CAL/ovton_config.yaml --init groundtruth -m sr --residual-log` and `ovton eval` (APE).
# calibrate_sweep.py then scores calibrate's estimate (against its own sigma: bar within 3 sigma) and the filter's
# last online-calibration row (RES_calib.csv; bars 0.3 deg, 1 %, 1 ms) against the truth of sim.yaml:
#   R_true = Exp(planted) R_BC(declared), f_true = 480 (1 + focal error), t_d truth at the middle row = td0 + t_r/2.
# Usage: scripts/experiments/calibrate_sweep.sh [OUT] [CASE...]   (default: every case; ~2 min per case)
#   OVTON_BIN overrides the binary (default build/ovton); KEEP=1 keeps renders and residual logs.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/calibrate_sweep}
shift || true
BIN=${OVTON_BIN:-build/ovton}
[ -x "$BIN" ] || { echo "no binary at $BIN (build first or set OVTON_BIN)" >&2; exit 1; }
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
cat >"$OUT/cam.yaml" <<'EOF'
%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0, -1.0, 0.0, 0.0,
         1.0, 0.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 30
resolution: [640, 480]
camera_model: pinhole
intrinsics: [480.0, 480.0, 320.0, 240.0]
distortion_model: radial-tangential
distortion_coefficients: [0.0, 0.0, 0.0, 0.0]
EOF

# name  rotation 'x,y,z' [deg]  focal error [%]  td0 [ms]  readout [ms]
CASES=(
  "c1 10,0,0 -15 -100 0"
  "c2 0,-10,0 15 100 0"
  "c3 0,0,10 15 -100 0"
  "c4 5.77,-5.77,5.77 -15 100 0"
  "c5 5,-4,3 8 60 0"
  "c6 -3,6,-2 -8 -40 0"
  "c7 4,-3,6 8 60 16"
  "c8 -7,-7,0 -8 -40 16"
  "c9 -6,0,8 15 -100 16"
  "c10 0,7.07,-7.07 -15 100 16"
)
WANT=("$@")

one() { # name rot focal td readout
  local name=$1 rot=$2 focal=$3 td=$4 ro=$5 t0
  local sim="$OUT/$name/sim" cal="$OUT/$name/cal"
  t0=$(date +%s)
  rm -rf "$OUT/$name"
  mkdir -p "$OUT/$name"
  echo "$name: rot $rot deg, focal $focal %, td0 $td ms, readout $ro ms" | tee "$OUT/$name/case.txt"
  nice -n 10 "$BIN" simulate -o "$sim" --duration-s 12 --td0-ms "$td" --focal-error-pct "$focal" \
    --extrinsic-rot-deg "$rot" --readout-ms "$ro" --cam-yaml "$OUT/cam.yaml" --agility 1 -q \
    >"$OUT/$name/simulate.log" 2>&1
  rm -f "$sim/mav0/cam0/sensor.yaml" "$sim/mav0/imu0/sensor.yaml"
  nice -n 10 "$BIN" calibrate -d "$sim" --out "$cal" >"$OUT/$name/calibrate.log" 2>&1 ||
    echo "calibrate exit $?" >>"$OUT/$name/case.txt"
  mkdir -p "$cal/mav0" # (calibrate failed: the run below fails and says so)
  ln -s "$sim/mav0/state_groundtruth_estimate0" "$cal/mav0/state_groundtruth_estimate0"
  ln -s "$sim/mav0/td_truth" "$cal/mav0/td_truth"
  local rc=0
  nice -n 10 "$BIN" run -d "$cal" -c "$cal/ovton_config.yaml" --init groundtruth -m sr -q \
    --residual-log "$OUT/$name/res.csv" -o "$OUT/$name/traj.csv" >"$OUT/$name/run.log" 2>&1 || rc=$?
  echo "run exit $rc" >>"$OUT/$name/case.txt"
  nice -n 10 "$BIN" eval --est "$OUT/$name/traj.csv" --gt "$sim/mav0/state_groundtruth_estimate0/data.csv" \
    --json "$OUT/$name/eval.json" >"$OUT/$name/eval.log" 2>&1 || echo "eval exit $?" >>"$OUT/$name/case.txt"
  if [ "${KEEP:-0}" != 1 ]; then # keep sim.yaml (the truth), the calibration, the calibration log, the trajectory
    rm -f "$OUT/$name/res.csv"
    rm -rf "$sim/mav0/cam0/data"
  fi
  echo "wall $(($(date +%s) - t0)) s" | tee -a "$OUT/$name/case.txt"
}

for c in "${CASES[@]}"; do
  read -r name rot focal td ro <<<"$c"
  if [ ${#WANT[@]} -gt 0 ] && [[ ! " ${WANT[*]} " == *" $name "* ]]; then continue; fi
  one "$name" "$rot" "$focal" "$td" "$ro"
done
"$PY" scripts/experiments/calibrate_sweep.py "$OUT" | tee "$OUT/table.md"
