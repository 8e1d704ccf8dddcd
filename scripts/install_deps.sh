#!/usr/bin/env bash
# Installs the Debian packages the build needs, and any given as arguments (skips apt when everything is already there).
# --minimal: what the `ovton` binary needs (scripts/quickstart.sh): OpenCV's six modules one by one instead of the
# libopencv-dev metapackage (every module, with Qt, VTK, FFmpeg, ...), no python3; GoogleTest stays (0.6 MB), so that
# the build folder is configured as scripts/test.sh configures it; ninja-build (0.1 MB), with which the quickstart's cold
# build keeps both cores busy to the end (docs/quickstart.md). cmake/ovtonOpenCV.cmake finds the modules without
# OpenCVConfig.cmake; what it saves: docs/quickstart.md, "What apt installs".
# --sanitize adds clang and its runtime libraries (ASan, UBSan, libFuzzer) for scripts/sanitize.sh and scripts/fuzz.sh;
# other arguments are extra packages a script needs (check_format.sh: clang-format).
set -euo pipefail
# librosbag-storage-dev + libsensor-msgs-dev: ROS 1 bags read and written without ROS (Debian's rosbag storage library);
# libroscpp-core-dev (roscpp_serialization, rostime, cpp_common), libconsole-bridge-dev and libroslz4-dev (the bag check
# decompresses lz4 chunks, rosbag_check.cpp) are linked directly, so named.
# libboost-dev: Boost.Math's headers (χ² and F distributions: the χ² gate, diagnose's Wald tests).
# libdeflate-dev: the fast decoder of 8-bit gray PNGs (ov_core/io/png_gray.cpp; optional in CMake, cv::imread without).
# libzstd-dev, liblz4-dev, zlib1g-dev, libsqlite3-dev: MCAP chunks (zstd, lz4, CRC-32) and rosbag2 .db3 files; the MCAP
# and CDR parsing is ovton's own (no library for them is packaged).
PKGS=(build-essential cmake ccache libeigen3-dev libyaml-cpp-dev libboost-dev libboost-program-options-dev
      librosbag-storage-dev libsensor-msgs-dev libroscpp-core-dev libconsole-bridge-dev libroslz4-dev libdeflate-dev
      libzstd-dev liblz4-dev zlib1g-dev libsqlite3-dev)
OPENCV_MODULES=(libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-video-dev
                libopencv-features2d-dev libopencv-calib3d-dev)
MINIMAL=("${OPENCV_MODULES[@]}" libgtest-dev ninja-build)
FULL=(libopencv-dev libgtest-dev python3)
MINIMAL_ONLY=""
for a in "$@"; do
  if [ "$a" = "--minimal" ]; then
    FULL=("${MINIMAL[@]}")
    MINIMAL_ONLY=yes
  elif [ "$a" = "--sanitize" ]; then
    PKGS+=(clang libclang-rt-14-dev)
  else
    PKGS+=("$a")
  fi
done
PKGS+=("${FULL[@]}")
# The MCAP writer and reader that are not ovton's own (scripts/mcap_tools: Foxglove's @mcap/core, its ROS 2 CDR
# serializer), for the tests that check ovton's MCAP files against them (tests/test_mcap_external.cpp). Optional:
# without node/npm or the registry those tests skip with a message.
npm_tools() {
  local dir
  dir="$(dirname "$0")/mcap_tools"
  [ -d "$dir/node_modules/@mcap/core" ] && return 0
  if ! command -v npm >/dev/null 2>&1; then
    echo "install_deps: npm not found: the independent MCAP writer's tests will skip (apt-get install nodejs npm)"
    return 0
  fi
  if timeout 300 npm ci --prefix "$dir" --no-audit --no-fund --loglevel=error >/dev/null 2>&1; then
    echo "install_deps: npm packages of scripts/mcap_tools installed"
  else
    echo "install_deps: npm ci in scripts/mcap_tools failed (offline?): the independent MCAP writer's tests will skip"
  fi
}
[ -n "$MINIMAL_ONLY" ] || npm_tools # the quickstart runs no test

missing=()
for p in "${PKGS[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install_deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
