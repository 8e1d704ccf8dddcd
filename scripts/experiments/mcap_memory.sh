#!/usr/bin/env bash
# Issue #38: a 1 GB MCAP replays in flat memory and as fast as its folder. Renders a long built-in flight (clean
# realism: a small PNG folder), writes it as an MCAP file with raw images (uncompressed chunks: the 1 GB file; zstd
# chunks) and as a ROS 1 bag, and replays the folder, each MCAP and the bag with `ovton run` under /usr/bin/time -v:
# peak RSS, wall time, CPU time, images per second of wall time; REPEATS rounds of the four replays, interleaved so
# that a busy machine slows them alike, summarised by their medians. The folder, files and runs are deleted at the end.
# Writes OUT/summary.md. Usage: scripts/experiments/mcap_memory.sh [OUT] [LONG_S] [REPEATS]  (~25 min, 2 busy cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/mcap_memory}
LONG_S=${2:-150}
REPEATS=${3:-3}
BIN=$PWD/build/ovton
CFG=config/sim/estimator_config.yaml
SCRATCH=$(mktemp -d /tmp/ovton_mcap_memory.XXXXXX)
trap 'rm -rf "$SCRATCH"' EXIT
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
ROWS="$OUT/rows.tsv"
: > "$ROWS"
DS="$SCRATCH/flight"
nice -n 10 "$BIN" simulate --builtin --realism clean --duration-s "$LONG_S" --seed 1 --out "$DS" -q >/dev/null
nice -n 10 "$BIN" export --dataset "$DS" --out "$SCRATCH/none.mcap" --compression none --no-kalibr -q >/dev/null
nice -n 10 "$BIN" export --dataset "$DS" --out "$SCRATCH/zstd.mcap" --no-kalibr -q >/dev/null
nice -n 10 "$BIN" export --dataset "$DS" --bag "$SCRATCH/flight.bag" --no-kalibr -q >/dev/null
# The folder's calibration for the recordings, without its images (a recording must not find them anywhere else).
CAL="$SCRATCH/calib"
mkdir -p "$CAL/mav0"
cp -r "$DS/mav0/cam0" "$DS/mav0/imu0" "$DS/mav0/state_groundtruth_estimate0" "$CAL/mav0/"
rm -rf "$CAL/mav0/cam0/data"
replay() { # name, dataset, extra args
  local name=$1 data=$2
  shift 2
  local time="$SCRATCH/time_$name.txt"
  nice -n 10 /usr/bin/time -v "$BIN" run --dataset "$data" "$@" -c "$CFG" -o "$SCRATCH/traj_$name.csv" -q \
    > "$SCRATCH/run_$name.txt" 2> "$time"
  local mb rss wall cpu images
  mb=$(du -m --apparent-size "$data" | tail -1 | awk '{print $1}')
  rss=$(awk -F: '/Maximum resident set size/ {printf "%.0f", $2 / 1024}' "$time")
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, p, ":"); s = 0; for (i = 1; i <= n; ++i) s = s * 60 + p[i]; print s}' "$time")
  cpu=$(awk -F': ' '/User time/ {u = $2} /System time/ {s = $2} END {print u + s}' "$time")
  images=$(cat "$SCRATCH/run_$name.txt" "$time" | grep -oE '^mode [^:]+: [0-9]+ images' | grep -oE '[0-9]+ images' |
    grep -oE '[0-9]+')
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$mb" "$images" "$rss" "$wall" "$cpu" \
    "$(awk -v n="$images" -v w="$wall" 'BEGIN {printf "%.1f", n / w}')" >> "$ROWS"
  if [ "$ROUND" = 1 ]; then
    cmp -s "$SCRATCH/traj_$name.csv" "$SCRATCH/traj_folder.csv" && echo "$name: same trajectory as the folder" \
      >> "$OUT/identical.txt" || echo "$name: trajectory DIFFERS from the folder's" >> "$OUT/identical.txt"
  fi
}
: > "$OUT/identical.txt"
for ROUND in $(seq 1 "$REPEATS"); do
  replay folder "$DS"
  replay mcap-none "$SCRATCH/none.mcap" --calib "$CAL"
  replay mcap-zstd "$SCRATCH/zstd.mcap" --calib "$CAL"
  replay rosbag "$SCRATCH/flight.bag" --calib "$CAL"
done
{
  echo "Made by \`scripts/experiments/mcap_memory.sh $OUT $LONG_S $REPEATS\` ($(date -u +%F), commit $(git rev-parse --short HEAD));"
  echo "data: \`ovton simulate --builtin --realism clean --duration-s $LONG_S --seed 1\`, then \`ovton export --no-kalibr\`"
  echo "to MCAP (\`--compression none\` and zstd, raw mono8 images) and to a ROS 1 bag; run: \`ovton run --dataset D"
  echo "-c $CFG\` (recordings with \`--calib\` the folder's calibration without its images), under /usr/bin/time -v;"
  echo "$REPEATS rounds, medians (each round's values in rows.tsv)."
  echo
  echo "| replayed | size [MB] | images | peak RSS [MB] | wall [s] | CPU [s] | images per wall second | vs folder |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|"
  python3 - "$ROWS" <<'PY'
import statistics as st, sys
rows = {}
for line in open(sys.argv[1]):
    name, mb, n, rss, wall, cpu, rate = line.split("\t")
    rows.setdefault(name, []).append((int(mb), int(n), float(rss), float(wall), float(cpu), float(rate)))
folder_rate = st.median(r[5] for r in rows["folder"])
for name, rs in rows.items():
    med = lambda i: st.median(r[i] for r in rs)
    print(f"| {name} | {rs[0][0]} | {rs[0][1]} | {med(2):.0f} | {med(3):.1f} | {med(4):.1f} | {med(5):.1f} | {med(5) / folder_rate:.2f} |")
PY
  echo
  cat "$OUT/identical.txt"
} > "$OUT/summary.md"
cat "$OUT/summary.md"
