#!/usr/bin/env bash
# Installs the Debian packages the build needs, and any given as arguments (skips apt when everything is already there).
# --minimal: what the `ovton` binary needs (scripts/quickstart.sh): OpenCV's six modules one by one instead of the
# libopencv-dev metapackage (every module, with Qt, VTK, FFmpeg, ...), no python3; GoogleTest stays (0.6 MB), so that
# the build folder is configured as scripts/test.sh configures it. cmake/ovtonOpenCV.cmake finds the modules without
# OpenCVConfig.cmake; what it saves: docs/quickstart.md, "What apt installs".
# --sanitize adds clang and its runtime libraries (ASan, UBSan, libFuzzer) for scripts/sanitize.sh and scripts/fuzz.sh;
# other arguments are extra packages a script needs (check_format.sh: clang-format).
set -euo pipefail
# librosbag-storage-dev + libsensor-msgs-dev: ROS 1 bags read and written without ROS (Debian's rosbag storage library);
# libroscpp-core-dev (roscpp_serialization, rostime, cpp_common) and libconsole-bridge-dev are linked directly, so named.
# libboost-dev: Boost.Math's headers (χ² and F distributions: the χ² gate, diagnose's Wald tests).
# libdeflate-dev: the fast decoder of 8-bit gray PNGs (ov_core/io/png_gray.cpp; optional in CMake, cv::imread without).
PKGS=(build-essential cmake ccache libeigen3-dev libyaml-cpp-dev libboost-dev libboost-program-options-dev
      librosbag-storage-dev libsensor-msgs-dev libroscpp-core-dev libconsole-bridge-dev libdeflate-dev)
OPENCV_MODULES=(libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-video-dev
                libopencv-features2d-dev libopencv-calib3d-dev)
MINIMAL=("${OPENCV_MODULES[@]}" libgtest-dev)
FULL=(libopencv-dev libgtest-dev python3)
for a in "$@"; do
  if [ "$a" = "--minimal" ]; then
    FULL=("${MINIMAL[@]}")
  elif [ "$a" = "--sanitize" ]; then
    PKGS+=(clang libclang-rt-14-dev)
  else
    PKGS+=("$a")
  fi
done
PKGS+=("${FULL[@]}")
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
