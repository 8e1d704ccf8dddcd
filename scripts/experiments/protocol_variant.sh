#!/usr/bin/env bash
# One mode of the paper's protocol (workflow/) re-run on its stored Table III folders with config keys overridden,
# the record of each cell written by the workflow's own run_case.py; prints the means the protocol tables report.
# Usage: scripts/experiments/protocol_variant.sh OUT PROTOCOL_DATA MODE [SECTION.KEY=VALUE ...]
#   PROTOCOL_DATA: the workflow's data/ folder (e.g. results/protocol_s24/data); cells t3_*_s1 (one seed each).
#   OVTON_BIN (default build/ovton), CONFIG (default config/sim/estimator_config.yaml), CELLS (glob, default t3_*_s1).
# Example: ... OUT results/protocol_s24/data drift imu.noise_multiplier=0.5
set -euo pipefail
cd "$(dirname "$0")/../.."
USAGE="usage: protocol_variant.sh OUT PROTOCOL_DATA MODE [SECTION.KEY=VALUE ...]"
OUT=${1:?$USAGE}
DATA=${2:?$USAGE}
MODE=${3:?$USAGE}
shift 3
BIN=${OVTON_BIN:-build/ovton}
CONFIG=${CONFIG:-config/sim/estimator_config.yaml}
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
python3 scripts/config_override.py "$CONFIG" "$OUT/config.yaml" "$@"
n=0
for d in "$DATA"/${CELLS:-t3_*_s1}; do
  [ -f "$d/sim.yaml" ] || continue
  python3 workflow/scripts/run_case.py --ovton "$BIN" --dataset "$d" --mode "$MODE" --config "$OUT/config.yaml" \
    --out "$OUT/$(basename "$d").json"
  n=$((n + 1))
done
[ "$n" -gt 0 ] || { echo "no protocol folders matching ${CELLS:-t3_*_s1} in $DATA" >&2; exit 1; }
python3 - "$OUT" "$MODE" "$*" <<'PY'
import glob, json, os, statistics, sys
out, mode, sets = sys.argv[1:4]
recs = [json.load(open(f)) for f in sorted(glob.glob(os.path.join(out, "*.json"))) if not f.endswith("_eval.json")]
ok = [r for r in recs if r.get("status") == "ok" and r.get("td_nees") is not None]
def mean(k):
    return statistics.mean(r[k] for r in ok)
line = (f"{mode} [{sets or 'as shipped'}]: {len(ok)} of {len(recs)} cells ok; t_d NEES {mean('td_nees'):.2f} "
        f"(per cell {' '.join('%.2f' % r['td_nees'] for r in ok)}), t_d RMSE second half {mean('td_err_rmse_late_ms'):.3f} ms, "
        f"TPE {mean('tpe_rmse_mm'):.3f} mm, APE {1e3 * mean('ape_rmse_m'):.1f} mm") if ok else f"{mode}: no cell ok"
print(line)
open(os.path.join(out, "summary.txt"), "w").write(line + "\n")
PY
