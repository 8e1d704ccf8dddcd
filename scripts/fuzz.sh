#!/usr/bin/env bash
# Runs libFuzzer targets on the readers for a given time each:
#   scripts/fuzz.sh csv|euroc|yaml|trajectory|mcap|rosbag|all SECONDS
# (mcap: MCAP files and their ROS 2 CDR messages; rosbag: ROS 1 bags. Their seeds are made by fuzz/make_seeds.sh.)
# Builds them with scripts/sanitize.sh's configuration (build-asan/) if needed. The corpus grows in
# build-asan/fuzz/corpus/TARGET, seeded from fuzz/corpus/TARGET; a finding (crash, sanitizer report, uncaught
# exception other than DataError/UsageError, timeout, memory blow-up) is saved in build-asan/fuzz/findings/ and the
# script exits non-zero. Prints one line per target: runs, executions per second, coverage.
set -euo pipefail
cd "$(dirname "$0")/.."
TARGET=${1:?usage: scripts/fuzz.sh csv|euroc|yaml|trajectory|mcap|rosbag|all SECONDS}
SECS=${2:?usage: scripts/fuzz.sh TARGET SECONDS}
TARGETS=(csv euroc yaml trajectory mcap rosbag)
[ "$TARGET" = all ] || TARGETS=("$TARGET")
JOBS=${JOBS:-$(nproc)}
if [ ! -f build-asan/CMakeCache.txt ]; then
  scripts/install_deps.sh --sanitize
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DOVTON_FUZZ=ON >/dev/null
fi
cmake --build build-asan -j"$JOBS" --target "${TARGETS[@]/#/fuzz_}" >/dev/null
# Each input is written to files before the readers see it: in memory when /dev/shm is there.
[ -d /dev/shm ] && [ -w /dev/shm ] && export TMPDIR=/dev/shm
status=0
for t in "${TARGETS[@]}"; do
  corpus=build-asan/fuzz/corpus/$t findings=build-asan/fuzz/findings/$t
  mkdir -p "$corpus" "$findings"
  log=build-asan/fuzz/$t.log
  # A recording's seeds (several messages and images) are larger than a text file's.
  max_len=16384
  case $t in mcap | rosbag) max_len=65536 ;; esac
  set +e
  ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1} UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
    build-asan/fuzz/fuzz_"$t" "$corpus" "fuzz/corpus/$t" -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 \
    -max_len=$max_len -artifact_prefix="$findings/" -print_final_stats=1 >"$log" 2>&1
  rc=$?
  set -e
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  if [ $rc -eq 0 ]; then
    echo "fuzz $t: ${SECS} s, $runs runs ($((${runs/\?/0} / (SECS > 0 ? SECS : 1))) /s), coverage $cov, no finding"
  else
    echo "fuzz $t: FINDING after $runs runs (exit $rc); see $log and $findings/"
    tail -40 "$log"
    status=1
  fi
done
exit $status
