#!/usr/bin/env bash
# Issue #16's worked cases: one undeclared effect planted per folder -> `sr` (effect not modelled) -> diagnose names
# and sizes it -> the matching `calibration` option (or t_d model) turned on -> APE/ARE/TPE and NEES before and after,
# and diagnose re-run (it reads the filter's calibration log beside the residual log, so an effect the filter has
# estimated is no longer named). Plus the clean flight: diagnose must flag nothing, and all calibration options on must not
# hurt it.
# Data: feature-level simulations (`ovton simulate --features-only`, 1 px noise, EuRoC ADIS16448 IMU noise) along the
# built-in flight with agility 1 (angular accelerations like EuRoC's medium sequences: a readout and the gyro's
# errors show in rates through the rotation), 30 s, seed SEED, constant offset 10 ms unless the case plants another.
# Usage: scripts/experiments/diagnose_undeclared.sh [OUT] [CASE ...]   cases: clean rolling_shutter focal extrinsic_rotation
#        gyro_scale_z accel_scale wander_td (default: all; ~1 min each here). OVTON_BIN overrides the binary, SEED
#        the seed (default 1). Writes OUT/undeclared.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/diagnose_undeclared}
shift || true
CASES=("$@")
[ ${#CASES[@]} -eq 0 ] && CASES=(clean rolling_shutter focal extrinsic_rotation gyro_scale_z accel_scale wander_td)
BIN=${OVTON_BIN:-build/ovton}
SEED=${SEED:-1}
source scripts/experiments/run_summary.sh
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"

# What each case plants (simulate options) and the model that matches it (YAML of the `after` run).
plant() {
  case $1 in
  clean) echo "" ;;
  rolling_shutter) echo "--readout-ms 20" ;;
  focal) echo "--focal-error-pct 1" ;;
  extrinsic_rotation) echo "--extrinsic-rot-deg 0.3,-0.4,0.5" ;;
  gyro_scale_z) echo "--gyro-scale-axes-pct 0,0,3" ;;
  accel_scale) echo "--accel-scale-axes-pct 3,3,3" ;;
  wander_td) echo "--td-model wander --td-wander-ms 8 --td-wander-period-s 10" ;;
  esac
}
# The IMU-intrinsics prior as in config/sim (0.3 %: the simulated IMU is the ADIS16448 as measured on real V1_01).
model() {
  case $1 in
  clean) printf 'calibration:\n  extrinsics: true\n  intrinsics: true\n  readout: true\n  imu_intrinsics: true\n  sigma_imu_intrinsics: 0.003\n' ;;
  rolling_shutter) printf 'calibration:\n  readout: true\n  sigma_readout_s: 0.02\n' ;;
  focal) printf 'calibration:\n  intrinsics: true\n' ;;
  extrinsic_rotation) printf 'calibration:\n  extrinsics: true\n' ;;
  gyro_scale_z | accel_scale) printf 'calibration:\n  imu_intrinsics: true\n  sigma_imu_intrinsics: 0.003\n' ;;
  # A wander of ±8 ms over 10 s moves the offset by up to 5 ms/s: t_d random walk of 3 ms/sqrt(s).
  wander_td) printf 'time_offset:\n  process: random_walk\n  random_walk: 3.0e-3\n' ;;
  esac
}

top() { # diagnose.json -> "key: estimates" of the first explained candidate, or the unexplained verdict
  python3 - "$1" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
c = next((c for c in d["candidates"] if c["explained"]), None)
u = [u for u in d.get("unexplained", []) if u["flagged"]]
s = "nothing flagged" if c is None else c["key"] + ": " + "; ".join(
    f"{e['name']} {e['value']:.3g} ± {e['stderr']:.2g} {e['unit']}" for e in c["estimates"][:3])
if u:
    s += " / UNEXPLAINED by " + ", ".join(f"{x['where']} ({100*x['explained']:.1f} %, {x['sigma']:.1f}σ)" for x in u)
print(s)
PY
}

{
  echo "# Undeclared effects: diagnose → model → re-run"
  echo
  echo "Made by \`scripts/experiments/diagnose_undeclared.sh $OUT ${CASES[*]}\` at commit $(git rev-parse --short HEAD)" \
    "(seed $SEED). Data: \`ovton simulate --builtin --agility 1 --duration-s 30 --features-only --seed $SEED" \
    "PLANT\`; runs: \`ovton run --td-mode sr --init groundtruth\` (sigma_px 1), before with the dataset's" \
    "calibration, after with the matching option on; NEES orientation / position averaged over the run (3 ideal)."
  echo
  echo "| case | planted | APE [m] before → after | ARE [deg] | TPE [mm] | NEES ori / pos | diagnose (before) |" \
    "after: diagnose |"
  echo "|---|---|---|---|---|---|---|---|"
} >"$OUT/undeclared.md"
declare -A V # one case's values: before.ape, after.diag, ...
for C in "${CASES[@]}"; do
  DS="$OUT/$C/data"
  read -r -a P <<<"$(plant "$C")"
  SIM=(simulate --out "$DS" --builtin --agility 1 --duration-s 30 --features-only --seed "$SEED" --force -q "${P[@]}")
  [ -d "$DS/mav0" ] && [ -f "$OUT/$C/.sim_args" ] && [ "$(cat "$OUT/$C/.sim_args")" = "${SIM[*]}" ] ||
    { "$BIN" "${SIM[@]}" >/dev/null && echo "${SIM[*]}" >"$OUT/$C/.sim_args"; }
  printf 'update:\n  sigma_px: 1.0\n' >"$OUT/$C/before.yaml"
  { printf 'update:\n  sigma_px: 1.0\n'; model "$C"; } >"$OUT/$C/after.yaml"
  for R in before after; do
    LINE=$("$BIN" run --dataset "$DS" --td-mode sr --config "$OUT/$C/$R.yaml" --init groundtruth \
      --output "$OUT/$C/$R.csv" --residual-log "$OUT/$C/${R}_res.csv" -q 2>"$OUT/$C/${R}_run.err" || true)
    echo "$LINE" >"$OUT/$C/${R}_run.txt"
    "$BIN" eval --est "$OUT/$C/$R.csv" --gt "$DS/mav0/state_groundtruth_estimate0/data.csv" \
      --td-truth "$DS/mav0/td_truth/data.csv" --json "$OUT/$C/${R}_eval.json" >/dev/null
    "$BIN" diagnose --log "$OUT/$C/${R}_res.csv" --dataset "$DS" --out "$OUT/$C/${R}_diagnose" \
      >"$OUT/$C/${R}_diagnose.txt"
    read -r APE ARE TPE < <(python3 -c "import json,sys; e=json.load(open(sys.argv[1])); \
print(f\"{e['ape_rmse_m']:.3f} {e['are_rmse_deg']:.3f} {e['tpe_rmse_mm'] or float('nan'):.2f}\")" \
      "$OUT/$C/${R}_eval.json")
    V[$R.ape]=$APE V[$R.are]=$ARE V[$R.tpe]=$TPE
    V[$R.nees]="$(nees_ori "$LINE") / $(nees_pos "$LINE")"
    V[$R.diag]=$(top "$OUT/$C/${R}_diagnose/diagnose.json")
  done
  echo "| $C | ${P[*]:-nothing} | ${V[before.ape]} → ${V[after.ape]} | ${V[before.are]} → ${V[after.are]} |" \
    "${V[before.tpe]} → ${V[after.tpe]} | ${V[before.nees]} → ${V[after.nees]} | ${V[before.diag]} |" \
    "${V[after.diag]} |" >>"$OUT/undeclared.md"
done
cat "$OUT/undeclared.md"
