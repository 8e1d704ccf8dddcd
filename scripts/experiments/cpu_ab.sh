#!/usr/bin/env bash
# Issue #15: whole-process CPU time (user + sys) of `ovton run --no-prefetch` for two or more ovton binaries,
# alternating binary by binary, REPS rounds, one OpenCV thread (binaries before `--opencv-threads` existed ran
# OpenCV's TBB pool anyway: compare like with like), under `nice -n 10`; prints per run the CPU seconds,
# the run's APE line and its per-frame stage times, so that a speed change is measured together with its accuracy.
# Usage: scripts/experiments/cpu_ab.sh OUT FOLDER CONFIG REPS BIN... (extra `ovton run` arguments in $EXTRA, e.g.
#        EXTRA="--init groundtruth" for real folders; THREADS=1 runs them threaded, as `ovton run` does by default,
#        instead of --no-prefetch). BIN's parent folder names the run (e.g. /tmp/x/base/ovton).
set -euo pipefail
[ $# -ge 5 ] || { sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
out=$1 f=$2 cfg=$3 reps=$4
shift 4
mkdir -p "$out"
one=--no-prefetch
[ -z "${THREADS:-}" ] || one=""
for r in $(seq 1 "$reps"); do
  for b in "$@"; do
    tag=$(basename "$(dirname "$b")")
    # shellcheck disable=SC2086
    OPENCV_FOR_THREADS_NUM=1 nice -n 10 /usr/bin/time -f "%U %S %e" -o "$out/${tag}_r$r.time" "$b" run -q $one \
      -d "$f" -c "$cfg" -m sr ${EXTRA:-} -o "$out/${tag}_r$r.csv" >"$out/${tag}_r$r.log" 2>&1
    echo "$tag r$r cpu $(awk '{print $1+$2}' "$out/${tag}_r$r.time") $(grep -E '^APE' "$out/${tag}_r$r.log") |" \
      "$(grep 'per frame' "$out/${tag}_r$r.log")"
  done
done
