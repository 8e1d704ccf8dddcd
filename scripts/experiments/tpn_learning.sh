#!/usr/bin/env bash
# Issue 36, "TON's learning on short and fast cases": how long TPN (modes tpn, ton) takes before its t_d beats the
# drift state's, on rendered flights whose offset drifts at RATES ms/s from 10 ms (`ovton simulate --td-model drift`,
# the drift model's 0.1 ms/sqrt(s) walk on top; rate 0 = a constant 10 ms). Flights: the built-in Lissajous at agility
# 1 (`builtin`) and EuRoC V1_02_medium from 5 s (`v102`), DUR s each. Every folder is run in every MODE ("label:ovton
# run args"; a SECTION.KEY=VALUE word overrides config/sim/estimator_config.yaml) and summarised by tpn_learning.py:
# per 1-s window the t_d error RMS against the folder's truth, the first second from which a mode stays below
# drift's, the last 10 s, final error / sigma, t_d NEES, TPE, APE, the model check's switch.
# Usage: scripts/experiments/tpn_learning.sh [OUT]   (~3.3 min per 40-s folder on one core: render 2 min, 7 runs)
#   OVTON_BIN the binary (default build/ovton), FLIGHTS ("builtin v102"), RATES ("0 0.1 0.5 1 2 3"), SEEDS ("1 2"),
#   ONE_SEED_RATES (rates rendered with the first seed only, default "0 0.1 0.5 2"), DUR (40), MODES (";"-separated
#   "label:args", default below), COMMIT (the binary's commit for the summary; default HEAD). Folders and runs already
#   in OUT are kept. Writes OUT/summary.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/tpn_learning}
BIN=$(realpath "${OVTON_BIN:-build/ovton}")
DUR=${DUR:-40}
CFG=config/sim/estimator_config.yaml
GT=../shared/data/euroc_groundtruth/V1_02_medium.txt
MODES=${MODES:-"sr:-m sr;drift:-m drift;oracle:-m oracle;tpn:-m tpn;ton:-m ton;\
tpn_nochk:-m tpn time_offset.model_check=false;ton_nochk:-m ton time_offset.model_check=false"}
IFS=';' read -r -a modes <<<"$MODES"
seeds=(${SEEDS:-1 2})
one_seed=" ${ONE_SEED_RATES-0 0.1 0.5 2} "
mkdir -p "$OUT/cfg"
for s in "${seeds[@]}"; do
  for flight in ${FLIGHTS:-builtin v102}; do
    for rate in ${RATES:-0 0.1 0.5 1 2 3}; do
      [ "$s" != "${seeds[0]}" ] && [[ $one_seed == *" $rate "* ]] && continue
      case=${flight}_r${rate}_s$s d=$OUT/data/$case
      if [ ! -f "$d/sim.yaml" ]; then
        path=(--builtin --agility 1)
        [ "$flight" = v102 ] && path=(--gt "$GT" --start-s 5)
        td=(--td-model drift --td0-ms 10 --td-bias-ms-per-s "$rate")
        [ "$rate" = 0 ] && td=(--td-model constant --td0-ms 10)
        echo "render $case" >&2
        nice -n 10 "$BIN" simulate "${path[@]}" --duration-s "$DUR" "${td[@]}" --seed "$s" --out "$d" --force -q >/dev/null
      fi
      mkdir -p "$OUT/runs/$case"
      for m in "${modes[@]}"; do
        label=${m%%:*} args=() sets=()
        for w in ${m#*:}; do
          if [[ $w =~ ^[a-z_]+\.[a-z_0-9]+= ]]; then sets+=("$w"); else args+=("$w"); fi
        done
        run=$OUT/runs/$case/$label
        grep -qs '^trajectory:' "$run.log" && continue
        vcfg=$CFG
        if [ ${#sets[@]} -gt 0 ]; then
          vcfg=$OUT/cfg/$label.yaml
          python3 scripts/config_override.py "$CFG" "$vcfg" "${sets[@]}" >/dev/null
        fi
        nice -n 10 "$BIN" run -d "$d" -c "$vcfg" "${args[@]}" -o "$run.csv" --no-prefetch >"$run.log" 2>&1 || true
      done
    done
  done
done
/usr/bin/python3 scripts/experiments/tpn_learning.py "$OUT" "${COMMIT:-$(git rev-parse --short HEAD)}" \
  >"$OUT/summary.md"
echo "wrote $OUT/summary.md" >&2
