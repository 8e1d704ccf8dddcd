#!/usr/bin/env bash
# Issue 36: does t_d's reported sigma hold when the offset moves faster than the mode's model allows? The real moving
# cut (../shared/data/euroc_v1_01_moving) with its image stamps rewritten by `ovton perturb`: constant offsets 0, +-40 ms
# and drifts of 0.1, 0.5, 1, 2, 3 ms/s from 10 ms (the drift model's own 0.1 ms/sqrt(s) walk on top), three seeds each;
# each run with the shipped EuRoC config and --init groundtruth, once per VARIANT ("label:extra ovton run args").
# Per run: the final |t_d - truth| in the run's own sigmas, the run's mean t_d NEES, APE, and whether the model check
# switched (the run's summary line). Prints one table (markdown) on stdout.
# Usage: scripts/experiments/td_model_check.sh OVTON OUT [VARIANT...]
#   default variants: "sr:-m sr" "sr_nocheck:-m sr --set time_offset.model_check=false" "drift:-m drift"
set -euo pipefail
[ $# -ge 2 ] || { sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
ovton=$(realpath "$1") out=$2
shift 2
here=$(cd "$(dirname "$0")/../.." && pwd)
cut=${CUT:-$here/../shared/data/euroc_v1_01_moving}
cfg=$here/config/euroc_mav/estimator_config.yaml
[ -d "$cut" ] || { echo "td_model_check: $cut not found" >&2; exit 2; }
[ $# -gt 0 ] || set -- "sr:-m sr" "drift:-m drift"
mkdir -p "$out"
cases=(const_0 const_40 const_-40)
for r in 0.1 0.5 1 2 3; do for s in 1 2 3; do cases+=("drift_${r}_s$s"); done; done
for c in "${cases[@]}"; do
  [ -d "$out/data/$c" ] && continue
  case $c in
  const_*) "$ovton" perturb -d "$cut" -o "$out/data/$c" --td-model constant --td0-ms "${c#const_}" >/dev/null ;;
  drift_*)
    r=${c#drift_}
    "$ovton" perturb -d "$cut" -o "$out/data/$c" --td-model drift --td0-ms 10 --td-bias-ms-per-s "${r%_s*}" \
      --seed "${r#*_s}" >/dev/null
    ;;
  esac
done
echo "| case | variant | final t_d - truth [ms] | sigma [ms] | in sigmas | mean t_d NEES | APE [mm] | switched |"
echo "|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  for v in "$@"; do
    label=${v%%:*} args=${v#*:}
    run=$out/runs/${c}_$label
    mkdir -p "$run"
    # shellcheck disable=SC2086
    if ! "$ovton" run -q -d "$out/data/$c" -c "$cfg" --init groundtruth $args -o "$run/traj.csv" \
      --nees-log "$run/nees.csv" >"$run/log" 2>&1; then
      echo "| $c | $label | run failed (exit $?): $(tail -1 "$run/log") | | | | | |"
      continue
    fi
    truth=$(tail -1 "$out/data/$c/mav0/td_truth/data.csv" | cut -d, -f2)
    est=$(tail -1 "$run/traj.csv" | awk -F, '{print $18, $19}')
    nees=$(awk -F, 'NR > 1 {s += $4; n++} END {printf "%.2f", s / n}' "$run/nees.csv")
    ape=$(grep -oE '^APE [0-9.]+' "$run/log" | awk '{printf "%.1f", $2 * 1000}')
    sw=$(grep -oE 't_d model check: switched[^;]*at [0-9.]+ s' "$run/log" | grep -oE '[0-9.]+ s$' || echo no)
    echo "$est $truth" | awk -v c="$c" -v l="$label" -v n="$nees" -v a="$ape" -v sw="$sw" \
      '{e = ($1 - $3) * 1e3; s = $2 * 1e3; printf "| %s | %s | %.2f | %.2f | %.1f | %s | %s | %s |\n", c, l, e, s, (e < 0 ? -e : e) / s, n, a, sw}'
  done
done
