#!/usr/bin/env bash
# The test command: install what is missing, build, run the whole GoogleTest suite through ctest.
# Tests that need ../shared/data skip with a message when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
cd build
ctest --output-on-failure -j"${JOBS:-$(nproc)}" --timeout 600
