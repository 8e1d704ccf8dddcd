#!/usr/bin/env bash
# CI's accuracy gate (docs/accuracy_gate.md): a few fixed cases whose APE, TPE and t_d error per mode must stay
# within a tolerance of the stored references (tests/accuracy_gate_reference.csv); a worsening beyond it exits 1 with
# a table of what moved. Cases: the real moving EuRoC cut (../shared/data/euroc_v1_01_moving) with its image stamps
# shifted by 0 (with the coarse t_d search) and +40 ms (`ovton perturb`; without the search), and a 10 s render of the built-in agile flight whose offset drifts
# 0.5 ms/s. Modes sr, drift, ton in each. ~1-2 min on 2 cores after the build.
#
#   scripts/accuracy_gate.sh                 check build/ovton against the references
#   scripts/accuracy_gate.sh --calibrate     rerun every case under 4 nuisance variants (update.sigma_px scaled by
#                                            1 +- 1e-4, 1 +- 2e-4: a change as small as reordered floating point)
#                                            and write the references with tolerance = max(3 x their spread, floor)
# Environment: OVTON (binary, default build/ovton), WORK (scratch folder, default a fresh temporary one),
# REF (reference file), DATA (the moving cut).
set -euo pipefail
cd "$(dirname "$0")/.."
OVTON=${OVTON:-build/ovton}
REF=${REF:-tests/accuracy_gate_reference.csv}
DATA=${DATA:-../shared/data/euroc_v1_01_moving}
WORK=${WORK:-$(mktemp -d)}
MODE=check
[ "${1:-}" = "--calibrate" ] && MODE=calibrate
[ -x "$OVTON" ] || {
  echo "accuracy_gate: $OVTON not found (build first: scripts/build.sh)"
  exit 2
}
mkdir -p "$WORK"
T0=$SECONDS

# A config with update.sigma_px (the first sigma_px line, in the update section) multiplied by $3, and with the coarse
# t_d search off when $4 is "nosearch".
scaled_config() {
  awk -v f="$3" -v nosearch="${4:-}" '
    !done && /^  sigma_px: / { printf "  sigma_px: %.9g\n", $2 * f; done = 1; next }
    { print }
    /^time_offset:/ && nosearch == "nosearch" { print "  search: false" }' "$1" >"$2"
}

# The cases' folders, made once.
CASES=()
if [ -d "$DATA/mav0" ]; then
  # 0 ms: the coarse search and the filter; +40 ms: the filter alone (search off) has to pull t_d from 0 to 40 ms.
  for td in 0 40; do
    d="$WORK/cut_${td}ms"
    [ -d "$d/mav0" ] || "$OVTON" perturb --dataset "$DATA" --out "$d" --td-model constant --td0-ms "$td" >/dev/null
    CASES+=("cut_${td}ms:$d:config/euroc_mav/estimator_config.yaml:--init groundtruth:$([ "$td" = 40 ] && echo nosearch || true)")
  done
else
  echo "accuracy_gate: $DATA absent: the real-cut cases are skipped (a fresh clone without ../shared/data)"
fi
d="$WORK/render_drift"
[ -d "$d/mav0" ] || "$OVTON" simulate --builtin --agility 1 --duration-s 10 --td-model drift --td0-ms 10 \
  --td-bias-ms-per-s 0.5 --seed 1 --out "$d" -q >/dev/null
CASES+=("render_drift:$d:config/sim/estimator_config.yaml::")

# Runs every case with the config scaled by $1; writes $WORK/<variant>.csv (case,mode,status,ape_mm,tpe_mm,td_err_ms).
run_variant() {
  local variant=$1 factor=$2 out="$WORK/$1.csv"
  echo "case,mode,status,ape_mm,tpe_mm,td_err_ms" >"$out"
  for c in "${CASES[@]}"; do
    IFS=: read -r name dir cfg extra search <<<"$c"
    scaled_config "$cfg" "$WORK/$name.$variant.yaml" "$factor" "$search"
    # shellcheck disable=SC2086 # extra holds whole options
    "$OVTON" compare --dataset "$dir" --config "$WORK/$name.$variant.yaml" $extra --modes sr,drift,ton \
      --out "$WORK/$name.$variant" >"$WORK/$name.$variant.log" 2>&1 || true
    if [ ! -f "$WORK/$name.$variant/results.csv" ]; then
      echo "accuracy_gate: compare wrote no results for $name ($WORK/$name.$variant.log):"
      tail -5 "$WORK/$name.$variant.log"
      exit 1
    fi
    awk -F, -v c="$name" 'NR > 1 { printf "%s,%s,%s,%.6f,%.6f,%.6f\n", c, $1, $2, $3 * 1000, $5, $12 }' \
      "$WORK/$name.$variant/results.csv" >>"$out"
  done
}

if [ "$MODE" = calibrate ]; then
  run_variant base 1
  i=0
  for f in 0.9998 0.9999 1.0001 1.0002; do
    run_variant "nuisance$((++i))" "$f"
  done
  python3 scripts/accuracy_gate.py calibrate "$REF" "$WORK/base.csv" "$WORK"/nuisance*.csv
  rc=0
else
  run_variant base 1
  rc=0
  python3 scripts/accuracy_gate.py check "$REF" "$WORK/base.csv" || rc=$?
fi
echo "accuracy_gate: $((SECONDS - T0)) s (work folder $WORK)"
exit $rc
