#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer, built by clang into build-asan/ (beside the
# normal build). Any report fails the test that triggered it. The same build holds the libFuzzer targets
# (scripts/fuzz.sh). Usage: scripts/sanitize.sh [--ci] [extra ctest args, e.g. -R Io]
#   --ci: leave out the 57 tests that replay whole flights (diagnose on filter logs, compare, TON, SLAM, calibration
#   and realism runs, bag replays of whole folders), for a quick check: under ASan+UBSan they take ~20x their Release
#   time (7.6 min of the whole suite's ~9 on two cores, docs/robustness.md). CI runs the whole suite.
set -euo pipefail
cd "$(dirname "$0")/.."
CTEST_ARGS=()
if [ "${1:-}" = "--ci" ]; then
  shift
  CTEST_ARGS=(-E '^(DiagnoseFilterLog|DiagnoseTruePoses|Diagnose|CompareTest|BagReal|TonFilter|SimRender|SimRealism|SimWriter|SlamRun|DynamicInitReal|PlusMinus20ms/RealMovingCut|TonVsRules|SimImuErrors|UpdateConsistency|CalibrationRun|TdSearchReal|VelocityTruth)\.|^ImagePrefetcher\.FilterGivesTheSameTrajectory|^BagTest\.(BagReplaysToTheByteIdenticalTrajectory|KalibrFilesBesideTheBag|TopicsChosenOrRefused|ReadsBackWhatWasWritten|UnsupportedEncodingNamesTheMessage)')
fi
scripts/install_deps.sh --sanitize
JOBS=${JOBS:-$(nproc)}
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DOVTON_FUZZ=ON >/dev/null
cmake --build build-asan -j"$JOBS"
cd build-asan
# abort_on_error: a report is a failed test, not a line in a log nobody reads.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --output-on-failure -j"$JOBS" --timeout 1800 "${CTEST_ARGS[@]}" "$@"
