#!/usr/bin/env bash
# Issue 36: `ovton diagnose` on an accelerometer scale error in realistic renders of real EuRoC flights the diagnosis
# was not tuned on (its sizing flights are the built-in Lissajous flight, seeds 1-7). Per flight: one rendering
# (`ovton simulate --gt SEQ.txt --realism euroc`, +10 ms constant offset), its IMU made again with `--no-images` and
# `--accel-scale-axes-pct P,P,P` for each P of PCTS (the same seed gives the same images, trajectory and offset, so
# the planted folder differs from its clean twin in the accelerometer alone), `ovton run --td-mode sr --init
# groundtruth` (config/sim), `ovton diagnose --dataset`. Prints and writes OUT/accel_renders.md: the first flagged
# candidate, the accel_scale estimate ± SE and its sigma, per flight and scale (0 = the clean twin).
# Usage: scripts/experiments/diagnose_accel_renders.sh OUT
#   FLIGHTS ("SEQ:START_S:SEED ...", default below), DUR (50 s), PCTS ("2 3"), OVTON_BIN, DIAGNOSE_ONLY=1 (re-diagnose
#   the runs in OUT). ~3 min per flight here (one render, three runs).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: diagnose_accel_renders.sh OUT}
FLIGHTS=${FLIGHTS:-"V1_02_medium:10:21 V2_02_medium:20:22 MH_04_difficult:20:23 V1_03_difficult:15:24"}
DUR=${DUR:-50}
PCTS=${PCTS:-"2 3"}
BIN=${OVTON_BIN:-$(pwd)/build/ovton}
[ -x "$BIN" ] || scripts/build.sh
GTDIR=../shared/data/euroc_groundtruth
mkdir -p "$OUT"
{
  echo "# diagnose: accelerometer scale on realistic renders (${DUR} s)"
  echo
  echo "Made by \`scripts/experiments/diagnose_accel_renders.sh $OUT\` at commit $(git rev-parse --short HEAD)" \
    "(FLIGHTS=\"$FLIGHTS\")."
  echo
  echo "| flight | seed | planted [%] | first flagged | accel_scale s [%] | sigma | named first | within 20 % |"
  echo "|---|---:|---:|---|---|---:|---|---|"
} >"$OUT/accel_renders.md"
for F in $FLIGHTS; do
  IFS=: read -r SEQ START SEED <<<"$F"
  BASE="$OUT/${SEQ}_s$SEED"
  IMG="$BASE/p0/data"
  if [ ! -f "$IMG/mav0/td_truth/data.csv" ]; then
    mkdir -p "$BASE/p0"
    nice -n 10 "$BIN" simulate --gt "$GTDIR/$SEQ.txt" --start-s "$START" --duration-s "$DUR" --seed "$SEED" \
      --realism euroc --out "$IMG" --force -q >"$BASE/p0/simulate.log" 2>&1
  fi
  for P in 0 $PCTS; do
    D="$BASE/p$P"
    DS="$D/data"
    if [ "$P" != 0 ] && [ ! -f "$DS/mav0/td_truth/data.csv" ]; then
      mkdir -p "$D"
      nice -n 10 "$BIN" simulate --gt "$GTDIR/$SEQ.txt" --start-s "$START" --duration-s "$DUR" --seed "$SEED" \
        --realism euroc --no-images --accel-scale-axes-pct "$P,$P,$P" --out "$D/imu" --force -q >"$D/simulate.log" 2>&1
      rm -rf "$DS" && mkdir -p "$DS/mav0"
      for d in "$IMG"/mav0/*; do ln -s "$(realpath "$d")" "$DS/mav0/$(basename "$d")"; done
      rm "$DS/mav0/imu0" "$DS/mav0/state_groundtruth_estimate0"
      cp -r "$D/imu/mav0/imu0" "$D/imu/mav0/state_groundtruth_estimate0" "$DS/mav0/"
      cmp -s "$D/imu/mav0/td_truth/data.csv" "$IMG/mav0/td_truth/data.csv" || { echo "offsets differ: $D" >&2; exit 1; }
    fi
    [ "${DIAGNOSE_ONLY:-0}" = 1 ] && [ -f "$D/res.csv" ] ||
      nice -n 10 "$BIN" run --dataset "$DS" --td-mode sr --config config/sim/estimator_config.yaml --init groundtruth \
        --output "$D/run.csv" --residual-log "$D/res.csv" -q >"$D/run.txt" 2>&1 || true
    nice -n 10 "$BIN" diagnose --log "$D/res.csv" --dataset "$DS" --out "$D/diagnose" >"$D/diagnose.txt"
    python3 - "$D/diagnose/diagnose.json" "$SEQ" "$SEED" "$P" >>"$OUT/accel_renders.md" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
pct = float(sys.argv[4])
first = next((c for c in d["candidates"] if c["explained"]), None)
flag = "nothing" if first is None else first["key"]
if any(u["flagged"] for u in d.get("unexplained", [])):
    flag += " + UNEXPLAINED"
c = next(c for c in d["candidates"] if c["key"] == "accel_scale")
e = next((x for x in c.get("estimates", []) if x["name"] == "accel scale error s"), None)
est = f"{e['value']:.2f} ± {e['stderr']:.2f}" if e else "- (" + c.get("note", "") + ")"
if pct == 0:
    named, within = "", ("clean: nothing flagged" if first is None and "UNEXPLAINED" not in flag else "FALSE FLAG")
else:
    named = "yes" if first is not None and first["key"] == "accel_scale" else "no"
    within = "yes" if e and abs(e["value"] - pct) <= 0.2 * pct else "no"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {pct:g} | {flag} | {est} | {c['sigma']:.1f} | {named} | {within} |")
PY
  done
done
cat "$OUT/accel_renders.md"
