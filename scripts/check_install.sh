#!/usr/bin/env bash
# The library as a program embeds it (issue 35), on a built tree (scripts/build.sh):
#  1. `cmake --install` into a fresh prefix;
#  2. examples/ configured and built against that prefix only (find_package(ovton));
#  3. the example streams a recording with jittered arrival (images ahead of their IMU, IMU in bursts) and its
#     trajectory must equal the installed `ovton run`'s on the same recording, byte for byte: the real moving EuRoC
#     cut when ../shared/data is there, else a feature-level flight simulated here;
#  4. no symbol of the installed libraries lives in a namespace OpenVINS uses (ov_core, ov_msckf, ov_init, ov_type,
#     ov_eval): a program can link both.
# Usage: scripts/check_install.sh [WORK_DIR]   (~1 min after the build)
set -euo pipefail
cd "$(dirname "$0")/.."
WORK=${1:-$(mktemp -d)}
mkdir -p "$WORK"
PREFIX="$WORK/prefix"
cmake --install build --prefix "$PREFIX" >/dev/null
cmake -S examples -B "$WORK/build-examples" -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$WORK/build-examples" -j"${JOBS:-2}" >/dev/null
echo "check_install: installed into $PREFIX, examples built against it"

if [ -d ../shared/data/euroc_v1_01_moving ]; then
  DATA=../shared/data/euroc_v1_01_moving
  CFG=config/euroc_mav/estimator_config.yaml
else
  DATA="$WORK/flight"
  CFG="$WORK/flight.yaml" # feature-level points with independent 1 px noise: the built-in defaults, from the truth
  printf 'init:\n  mode: groundtruth\n' >"$CFG"
  "$PREFIX/bin/ovton" simulate --builtin --features-only --duration-s 10 --seed 3 --out "$DATA" -q >/dev/null
fi
"$PREFIX/bin/ovton" run -q -c "$CFG" --dataset "$DATA" --output "$WORK/run.csv" >"$WORK/run.out"
"$WORK/build-examples/stream_euroc" "$DATA" "$CFG" "$WORK/example.csv" >"$WORK/example.out"
rows=$(($(wc -l <"$WORK/run.csv") - 1))
if ! cmp -s "$WORK/run.csv" "$WORK/example.csv"; then
  echo "check_install: FAILED: the example's trajectory differs from ovton run's ($WORK/run.csv, $WORK/example.csv)"
  exit 1
fi
echo "check_install: the example (jittered arrival, installed library) and ovton run agree byte for byte on $DATA" \
  "($rows states; $(tail -1 "$WORK/example.out"))"

bad=$(nm -C --defined-only "$PREFIX"/lib/*.a 2>/dev/null | awk '{ $1 = ""; $2 = ""; sub(/^ +/, ""); print }' |
  grep -E '^(ov_core|ov_msckf|ov_init|ov_type|ov_eval)::' | head -5 || true)
if [ -n "$bad" ]; then
  echo "check_install: FAILED: symbols in a namespace OpenVINS uses:"
  echo "$bad"
  exit 1
fi
echo "check_install: $(nm -C --defined-only "$PREFIX"/lib/*.a | grep -c ' [TW] ovton::') ovton:: functions defined," \
  "none in ov_core::, ov_msckf::, ov_init::, ov_type:: or ov_eval::"
