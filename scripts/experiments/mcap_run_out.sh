#!/usr/bin/env bash
# Issue #38: `ovton run --mcap-out` on the quickstart sample (the 20 s built-in flight, +10 ms offset, mode sr, as
# scripts/quickstart.sh runs it), read back by Foxglove's own reader (scripts/mcap_tools/check_mcap.mjs: @mcap/core's
# indexed reader, every chunk CRC, every message decoded by the schema the file carries). Prints each channel's schema
# and message count against the trajectory's rows, the file's size, and what the recording costs: the same run without
# --mcap-out, R rounds of the two interleaved (wall and CPU seconds, peak RSS; medians), trajectories compared byte for
# byte.
# Writes OUT/summary.md (and keeps OUT/run_sr.mcap to open in Foxglove). Needs node with scripts/mcap_tools' npm
# packages (npm ci --prefix scripts/mcap_tools). Usage: scripts/experiments/mcap_run_out.sh [OUT] [R]  (~2 min)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/mcap_run_out}
R=${2:-3}
BIN=$PWD/build/ovton
TOOLS=$PWD/scripts/mcap_tools
SCRATCH=$(mktemp -d /tmp/ovton_mcap_run_out.XXXXXX)
trap 'rm -rf "$SCRATCH"' EXIT
[ -x "$BIN" ] || scripts/build.sh
[ -d "$TOOLS/node_modules/@mcap/core" ] || npm ci --prefix "$TOOLS" --no-audit --no-fund
mkdir -p "$OUT"
SAMPLE="$SCRATCH/sample"
nice -n 10 "$BIN" simulate --builtin --duration-s 20 --td0-ms 10 --seed 1 --out "$SAMPLE" -q >/dev/null
RUN=(run -q -c config/sim/estimator_config.yaml --td-mode sr --dataset "$SAMPLE")
timed() { # label, args... -> appends "label wall cpu peak_rss_kb" to times.txt
  local label=$1
  shift
  /usr/bin/time -f "%e %U %S %M" -o "$SCRATCH/t" nice -n 10 "$BIN" "$@" >"$SCRATCH/$label.out"
  echo "$label $(awk '{printf "%s %.2f %s", $1, $2 + $3, $4}' "$SCRATCH/t")" >>"$SCRATCH/times.txt"
}
: >"$SCRATCH/times.txt"
for ((i = 1; i <= R; i++)); do
  timed plain "${RUN[@]}" -o "$SCRATCH/plain.csv"
  timed mcap "${RUN[@]}" -o "$SCRATCH/mcap.csv" --mcap-out "$OUT/run_sr.mcap"
done
node "$TOOLS/check_mcap.mjs" "$OUT/run_sr.mcap" >"$SCRATCH/check.json"
ROWS=$(($(wc -l <"$SCRATCH/mcap.csv") - 1))
SAME=$(cmp -s "$SCRATCH/plain.csv" "$SCRATCH/mcap.csv" && echo "byte-identical" || echo "DIFFERENT")
{
  echo "Made by \`scripts/experiments/mcap_run_out.sh $OUT $R\` ($(date -u +%F), commit $(git rev-parse --short HEAD))."
  echo "Sample: \`ovton simulate --builtin --duration-s 20 --td0-ms 10 --seed 1\`; run: \`ovton ${RUN[*]/$SAMPLE/SAMPLE} -o T.csv --mcap-out run_sr.mcap\`."
  echo "Read back by \`node scripts/mcap_tools/check_mcap.mjs run_sr.mcap\` (@mcap/core $(node -p "require('$TOOLS/node_modules/@mcap/core/package.json').version"))."
  echo
  python3 - "$SCRATCH/check.json" "$ROWS" "$(stat -c %s "$OUT/run_sr.mcap")" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
rows, size = int(sys.argv[2]), int(sys.argv[3])
print(f"File: {size / 1e6:.1f} MB, profile {j['profile']}, {j['messages']} messages in {j['chunks']} chunks, data CRC {j['dataCrc']}; trajectory rows: {rows}.")
print()
print("| topic | schema (as the file names it) | messages | decoded by its schema |")
print("|---|---|---:|---|")
for topic, t in j["topics"].items():
    print(f"| `{topic}` | `{t['schema']}` | {t['count']} | {'yes' if t['count'] == 0 or 'first' in t else 'NO'} |")
PY
  echo
  python3 - "$SCRATCH/times.txt" "$SAME" <<'PY'
import statistics, sys
t = {}
for line in open(sys.argv[1]):
    label, wall, cpu, rss = line.split()
    t.setdefault(label, []).append((float(wall), float(cpu), float(rss) / 1024))
m = {k: [statistics.median(x[i] for x in v) for i in range(3)] for k, v in t.items()}
n = len(t["plain"])
print(f"Cost, medians of {n} interleaved rounds: without --mcap-out {m['plain'][0]:.2f} s wall / {m['plain'][1]:.2f} s CPU, "
      f"with {m['mcap'][0]:.2f} s / {m['mcap'][1]:.2f} s ({m['mcap'][0] / m['plain'][0]:.2f}x / {m['mcap'][1] / m['plain'][1]:.2f}x); "
      f"peak RSS {m['plain'][2]:.0f} MB / {m['mcap'][2]:.0f} MB; trajectories {sys.argv[2]}.")
PY
} >"$OUT/summary.md"
cat "$OUT/summary.md"
