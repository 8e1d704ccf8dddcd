#!/usr/bin/env bash
# Issue #16, the rolling shutter: which image velocity should a row's shift V·ρ·t_r use — the track's measured one
# (noisy, absent on a track's first observation) or the one the state predicts (calibration.readout_state_velocity)?
# Per seed, the agile feature-level flight of diagnose_undeclared.sh (30 s, 1 px, `sr`, ground-truth initialisation)
# rendered clean and with a 20 ms readout; runs:
#   clean            the clean flight, nothing estimated (the reference APE)
#   clean_all        the clean flight with every calibration option on (the readout estimated from 0)
#   rs_none          the readout planted, not modelled
#   rs_known         the readout given (calibration.readout_s 0.02), not estimated
#   rs_est           the readout estimated from 0 (calibration.readout true, sigma 20 ms): the worked case's "after"
# each with the state's velocity (`state`, the default) and the tracked one (`tracked`).
# Usage: [OVTON_BIN=build/ovton] scripts/experiments/readout_velocity.sh [OUT] [SEEDS]   (SEEDS default "1 2 3 4";
#        ~1 min per seed here). Writes OUT/readout_velocity.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/readout_velocity}
SEEDS=${2:-1 2 3 4}
BIN=${OVTON_BIN:-build/ovton}
source scripts/experiments/run_summary.sh
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"

config() { # RUN VELOCITY -> YAML
  printf 'update:\n  sigma_px: 1.0\ncalibration:\n  readout_state_velocity: %s\n' "$([ "$2" = state ] && echo true || echo false)"
  case $1 in
  clean_all) printf '  extrinsics: true\n  intrinsics: true\n  readout: true\n  imu_intrinsics: true\n  sigma_imu_intrinsics: 0.003\n' ;;
  rs_known) printf '  readout_s: 0.02\n' ;;
  rs_est) printf '  readout: true\n  sigma_readout_s: 0.02\n' ;;
  esac
}
ROWS="$OUT/rows.txt"
: >"$ROWS"
for S in $SEEDS; do
  for KIND in clean rs; do
    DS="$OUT/s$S/$KIND"
    PLANT=()
    [ "$KIND" = rs ] && PLANT=(--readout-ms 20)
    [ -f "$DS/mav0/imu0/data.csv" ] || "$BIN" simulate --out "$DS" --builtin --agility 1 --duration-s 30 \
      --features-only --seed "$S" --force -q "${PLANT[@]}" >/dev/null
  done
  for RUN in clean clean_all rs_none rs_known rs_est; do
    DS="$OUT/s$S/$([ "${RUN%%_*}" = clean ] && echo clean || echo rs)"
    for VEL in state tracked; do
      # clean and rs_none shift nothing: the velocity choice cannot matter there, so run them once.
      { [ "$RUN" = clean ] || [ "$RUN" = rs_none ]; } && [ "$VEL" = tracked ] && continue
      B="$OUT/s$S/${RUN}_$VEL"
      config "$RUN" "$VEL" >"$B.yaml"
      LINE=$("$BIN" run --dataset "$DS" --td-mode sr --config "$B.yaml" --init groundtruth --output "$B.csv" \
        --residual-log "$B.res.csv" -q 2>"$B.err" || true)
      APE=$(ape_m "$LINE")
      ARE=$("$BIN" eval --est "$B.csv" --gt "$DS/mav0/state_groundtruth_estimate0/data.csv" |
        sed -n 's/^ARE rmse \([0-9.]*\) deg.*/\1/p')
      TR=$([ "$RUN" = rs_est ] || [ "$RUN" = clean_all ] &&
        python3 -c "import csv,sys; r=list(csv.DictReader(open(sys.argv[1]))); print(f\"{float(r[-1]['readout_s'])*1e3:.2f}\")" \
          "$B.res_calib.csv" || echo -)
      echo "$S $RUN $VEL ${APE:-nan} ${ARE:-nan} $(nees_ori "$LINE") $(nees_pos "$LINE") $TR" >>"$ROWS"
    done
  done
done
python3 - "$ROWS" "$OUT/readout_velocity.md" "$(git rev-parse --short HEAD)" "$SEEDS" <<'PY'
import sys, collections
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
by = collections.defaultdict(dict)
for s, run, vel, ape, are, no, npos, tr in rows:
    by[(run, vel)][s] = (float(ape), float(are), no, npos, tr)
seeds = sorted({r[0] for r in rows}, key=int)
clean = by[("clean", "state")]
out = [f"Made by `scripts/experiments/readout_velocity.sh` at commit {sys.argv[3]} (seeds {sys.argv[4]}): "
       "agile feature-level flight, 30 s, 1 px, `sr`, ground-truth initialisation. APE [mm] per seed, mean, and the "
       "mean of APE / the clean run's; NEES orientation / position per seed; final readout [ms] where estimated "
       "(planted 20).\n\n",
       "| run | velocity | APE per seed [mm] | mean | / clean | within 1.3× clean | NEES ori / pos | t̂_r [ms] |\n",
       "|---|---|---|---:|---:|---:|---|---|\n"]
for run in ["clean", "clean_all", "rs_none", "rs_known", "rs_est"]:
    for vel in ["state", "tracked"]:
        d = by.get((run, vel))
        if not d:
            continue
        apes = [d[s][0] * 1e3 for s in seeds]
        ratios = [d[s][0] / clean[s][0] for s in seeds]
        out.append(f"| {run} | {vel if run not in ('clean', 'rs_none') else '–'} | "
                   + ", ".join(f"{a:.1f}" for a in apes) + f" | {sum(apes)/len(apes):.1f} | "
                   + f"{sum(ratios)/len(ratios):.2f} | {sum(r <= 1.3 for r in ratios)} of {len(ratios)} | "
                   + ", ".join(f"{d[s][2]}/{d[s][3]}" for s in seeds) + " | "
                   + ", ".join(d[s][4] for s in seeds) + " |\n")
open(sys.argv[2], "w").write("".join(out))
print("".join(out))
PY
