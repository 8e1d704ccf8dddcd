#!/usr/bin/env bash
# Issue #4's experiment: rendered EuRoC-format folders along V1_02_medium, V1_03_difficult and MH_03_medium with a
# constant true offset of +10 ms; modes off (t_d = 0), sr and oracle. Writes OUT/summary.md (the README table) and
# one `ovton compare` folder per sequence (tables, plots, trajectories).
# Usage: scripts/experiments/td_convergence.sh [OUT] [DURATION_S]      (needs ../shared/data; ~10 min on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/td_convergence}
DUR=${2:-60}
GT=../shared/data/euroc_groundtruth
BIN=build/ovton
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
{
  echo "# Constant +10 ms offset on rendered EuRoC trajectories"
  echo
  echo "Made by \`scripts/experiments/td_convergence.sh $OUT $DUR\` ($(date -u +%F), commit $(git rev-parse --short HEAD))."
  echo "Each folder: \`ovton simulate --gt $GT/<SEQ>.txt --start-s 5 --duration-s $DUR --td0-ms 10 --seed 1\`;"
  echo "each run: \`ovton compare --modes off,sr,oracle --config config/sim/estimator_config.yaml\`."
  echo "CIT: first frame with |t̂_d − t_d| ≤ 1 ms and a frame-to-frame change ≤ 0.1 ms (20 frames = 1 s)."
  echo
  echo "| sequence | mode | APE [m] | ARE [deg] | TPE [mm] | final t̂_d [ms] | t_d σ [ms] | CIT [frames] |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$OUT/summary.md"
for SEQ in V1_02_medium V1_03_difficult MH_03_medium; do
  DS="$OUT/data_$SEQ"
  [ -d "$DS/mav0" ] || "$BIN" simulate --out "$DS" --gt "$GT/$SEQ.txt" --start-s 5 --duration-s "$DUR" --td0-ms 10 \
    --seed 1 -q
  "$BIN" compare --dataset "$DS" --modes off,sr,oracle --out "$OUT/$SEQ" --config config/sim/estimator_config.yaml \
    --jobs 2 >/dev/null
  # results.csv: mode,status,ape_rmse_m,are_rmse_deg,tpe_rmse_mm,cit_frames,final_td_ms,td_sigma_ms,...
  python3 - "$OUT/$SEQ/results.csv" "$SEQ" >> "$OUT/summary.md" <<'PY'
import csv, sys
for r in csv.DictReader(open(sys.argv[1])):
    f = lambda k, d=3: (f"{float(r[k]):.{d}f}" if r.get(k) not in (None, "") else "")
    print(f"| {sys.argv[2]} | {r['mode']} | {f('ape_rmse_m')} | {f('are_deg', 2)} | {f('tpe_rmse_mm', 2)} | "
          f"{f('final_td_ms', 2)} | {f('td_sigma_ms', 3)} | {r.get('cit_frames', '')} |")
PY
done
cat "$OUT/summary.md"
