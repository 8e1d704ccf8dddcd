#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer, built by clang into build-asan/ (beside the
# normal build). Any report fails the test that triggered it. The same build holds the libFuzzer targets
# (scripts/fuzz.sh). Usage: scripts/sanitize.sh [extra ctest args, e.g. -R Io]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh --sanitize
JOBS=${JOBS:-$(nproc)}
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DOVTON_FUZZ=ON >/dev/null
cmake --build build-asan -j"$JOBS"
cd build-asan
# abort_on_error: a report is a failed test, not a line in a log nobody reads.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --output-on-failure -j"$JOBS" --timeout 1800 "$@"
