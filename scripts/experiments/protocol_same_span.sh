#!/usr/bin/env bash
# Issue #11: where the health check stopped `sr` in a protocol run (its constant t_d could not follow the drifting
# offset), compare the other modes with it over the same span: each mode's trajectory cut at sr's last row, scored
# by `ovton eval` against the cell's ground truth and td_truth. Prints a Markdown table (APE and TPE over the span).
# Usage: [OVTON_BIN=build/ovton] [MODES="sr ton tpn drift sr+random_walk oracle"] \
#          scripts/experiments/protocol_same_span.sh PROTOCOL_OUT      (e.g. results/protocol_whole)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: protocol_same_span.sh PROTOCOL_OUT}
BIN=${OVTON_BIN:-build/ovton}
MODES=${MODES:-sr ton tpn drift sr+random_walk oracle}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
field() { sed -n "s/^$1 *\([0-9.]*\).*/\1/p"; }
echo "| cell | sr stopped at [s of the flight] | $(echo "$MODES" | sed 's/ / | /g') |"
echo "|---|---|$(for _ in $MODES; do printf -- '---|'; done)"
for RUN in "$OUT"/runs/*/; do
  CELL=$(basename "$RUN")
  python3 -c "import json,sys; sys.exit(json.load(open(sys.argv[1]))['status'] == 'ok')" "$RUN/sr.json" || continue
  DS="$OUT/data/$CELL/mav0"
  LAST=$(tail -n 1 "$RUN/sr.csv" | cut -d, -f1)
  FIRST=$(sed -n 2p "$RUN/sr.csv" | cut -d, -f1)
  ROW="| $CELL | $(python3 -c "print(f'{($LAST - $FIRST) * 1e-9:.1f}')")"
  for M in $MODES; do
    awk -F, -v L="$LAST" 'NR == 1 || $1 <= L' "$RUN/$M.csv" >"$TMP/est.csv"
    E=$("$BIN" eval --est "$TMP/est.csv" --gt "$DS/state_groundtruth_estimate0/data.csv" --td-truth "$DS/td_truth/data.csv")
    ROW+=" | $(echo "$E" | field 'APE RMSE \[m\]') m, TPE $(echo "$E" | field 'TPE RMSE \[mm\]') mm"
  done
  echo "$ROW |"
done
