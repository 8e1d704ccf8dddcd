#!/usr/bin/env bash
# Issue 36: does t_d's reported sigma hold when the offset moves faster than the mode's model allows? The real moving
# cut (../shared/data/euroc_v1_01_moving) with its image stamps rewritten by `ovton perturb`: constant offsets 0, +-40 ms
# and drifts of 0.1, 0.5, 1, 2, 3 ms/s from 10 ms (the drift model's own 0.1 ms/sqrt(s) walk on top), SEEDS seeds each
# (default 3);
# each run with the shipped EuRoC config and --init groundtruth, once per VARIANT ("label:extra ovton run args"; a
# SECTION.KEY=VALUE word among them overrides the config, scripts/config_override.py).
# Per run: the final t_d - truth, in the run's own sigmas too, the run's mean t_d NEES (over every row and over the rows
# from 1 s on), APE and when the t_d model check switched to the drift state (the run's summary line; "no" if never);
# then per variant the extremes, the mean over the cases and how many runs switched. Prints markdown on stdout. CUT
# overrides the folder.
# Usage: scripts/experiments/td_drift_real_cut.sh OVTON OUT [VARIANT...]   (default variants: "sr:-m sr" "drift:-m drift")
set -euo pipefail
[ $# -ge 2 ] || { sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
ovton=$(realpath "$1") out=$2
shift 2
here=$(cd "$(dirname "$0")/../.." && pwd)
cut=${CUT:-$here/../shared/data/euroc_v1_01_moving}
cfg=$here/config/euroc_mav/estimator_config.yaml
[ -d "$cut" ] || { echo "td_drift_real_cut: $cut not found" >&2; exit 2; }
[ $# -gt 0 ] || set -- "sr:-m sr" "drift:-m drift"
mkdir -p "$out"
: >"$out/rows.md"
cases=(const_0 const_40 const_-40)
for r in 0.1 0.5 1 2 3; do for s in $(seq 1 "${SEEDS:-3}"); do cases+=("drift_${r}_s$s"); done; done
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
echo "| case | variant | final t_d - truth [ms] | sigma [ms] | in sigmas | mean t_d NEES | t_d NEES from 1 s | APE [mm] | switched at [s] |"
echo "|---|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  for v in "$@"; do
    label=${v%%:*} args=() sets=()
    for w in ${v#*:}; do
      if [[ $w =~ ^[a-z_]+\.[a-z_0-9]+= ]]; then sets+=("$w"); else args+=("$w"); fi
    done
    run=$out/runs/${c}_$label
    mkdir -p "$run" "$out/cfg"
    vcfg=$cfg
    if [ ${#sets[@]} -gt 0 ]; then
      vcfg=$out/cfg/$label.yaml
      python3 "$here/scripts/config_override.py" "$cfg" "$vcfg" "${sets[@]}"
    fi
    if ! "$ovton" run -q -d "$out/data/$c" -c "$vcfg" --init groundtruth "${args[@]}" -o "$run/traj.csv" \
      --nees-log "$run/nees.csv" >"$run/log" 2>&1; then
      echo "| $c | $label | run failed: $(tail -1 "$run/log") | | | | | | |"
      continue
    fi
    truth=$(tail -1 "$out/data/$c/mav0/td_truth/data.csv" | cut -d, -f2)
    est=$(tail -1 "$run/traj.csv" | awk -F, '{print $18, $19}')
    nees=$(awk -F, 'NR == 2 {t0 = $1} NR > 1 && $4 != "nan" {s += $4; n++; if ($1 - t0 >= 1e9) {sl += $4; nl++}}
      END {printf "%.2f %.2f", s / n, sl / nl}' "$run/nees.csv")
    ape=$("$ovton" eval --est "$run/traj.csv" --gt "$out/data/$c/mav0/state_groundtruth_estimate0/data.csv" |
      awk '/^APE RMSE/ {printf "%.1f", $4 * 1000}')
    sw=$(grep -oE 't_d model check: switched to the drift state at [0-9.]+' "$run/log" | awk '{print $NF}' || true)
    echo "$est $truth $nees" | awk -v c="$c" -v l="$label" -v a="$ape" -v sw="${sw:-no}" '{e = ($1 - $3) * 1e3; s = $2 * 1e3
      printf "| %s | %s | %.2f | %.2f | %.1f | %s | %s | %s | %s |\n", c, l, e, s, (e < 0 ? -e : e) / s, $4, $5, a, sw}' |
      tee -a "$out/rows.md"
  done
done
# Per variant over the cases: the largest final error in sigmas, the NEES range and mean (all rows; from 1 s), APE, and
# the runs that switched (of them on a constant offset, where a switch is a false alarm).
echo
echo "| variant | largest final error [sigmas] | t_d NEES min-max (mean) | from 1 s: min-max (mean) | APE [mm] min-max | switched (on a constant) |"
echo "|---|---|---|---|---|---|"
for v in "$@"; do
  awk -F' [|] ' -v l="${v%%:*}" '$2 == l {k = $5 + 0; n = $6 + 0; m = $7 + 0; a = $8 + 0; c++
      if (c == 1 || k > kx) kx = k; if (c == 1 || n < n0) n0 = n; if (c == 1 || n > n1) n1 = n; ns += n
      if (c == 1 || m < m0) m0 = m; if (c == 1 || m > m1) m1 = m; ms += m; if (c == 1 || a < a0) a0 = a; if (c == 1 || a > a1) a1 = a
      if ($9 + 0 > 0 || $9 ~ /^0/) {sw++; if ($1 ~ /const_/) swc++}}
    END {if (c) printf "| %s | %.1f | %.2f-%.2f (%.2f) | %.2f-%.2f (%.2f) | %.1f-%.1f | %d of %d (%d) |\n", l, kx, n0, n1, ns / c, m0, m1, ms / c, a0, a1, sw, c, swc}' \
    "$out/rows.md"
done
