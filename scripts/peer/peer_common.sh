# Sourced by the scripts that run OpenVINS through our harness copy (scripts/peer/openvins_vs_ovton.sh,
# scripts/experiments/phone_peer.sh): how that harness is built and what each OpenVINS variant's keys are.
# Needs REPO (the repository's root) set by the caller.

# OpenVINS's CMake finds Debian's ament_cmake, whose templates need the system Python's ament_package (a pyenv or
# venv python3 first on PATH lacks it).
PY_ARGS=()
[ -x /usr/bin/python3 ] && PY_ARGS=(-DPython3_EXECUTABLE=/usr/bin/python3)

# The OpenVINS library's own CXX flags: with Eigen in its interface, a harness built for another instruction set than
# the library crashes (e.g. a -march=native library).
ov_cxx_flags() { # OV_ROOT
  sed -n 's/^CMAKE_CXX_FLAGS:STRING=//p' "$1/build/CMakeCache.txt" 2>/dev/null || true
}

# Builds scripts/peer's ov_euroc_harness (stereo, init=ov, camchain=, td0=) in BUILD_DIR against OV_ROOT's library;
# extra arguments run the build (e.g. `flock LOCK`), niced, with JOBS jobs.
build_peer_harness() { # OV_ROOT BUILD_DIR JOBS [wrapper ...]
  local ov_root=$1 dir=$2 jobs=$3
  shift 3
  cmake -S "$REPO/scripts/peer" -B "$dir" -DOV_ROOT="$ov_root" -DCMAKE_BUILD_TYPE=Release "${PY_ARGS[@]}" \
    -DCMAKE_CXX_FLAGS="$(ov_cxx_flags "$ov_root")" >/dev/null
  "$@" nice -n 10 make -C "$dir" -j"$jobs" ov_euroc_harness >/dev/null
}

# The harness's keys for an OpenVINS variant: VARIANT[@ptsN] (docs/peer.md).
ov_args() {
  if [[ $1 == *@pts* ]]; then local n=${1##*@pts}; echo -n "num_pts=${n%%@*} "; fi
  case "${1%%@*}" in
  noslam) echo "" ;;
  default) echo "max_slam=50 calib_ext=1 calib_int=1" ;;
  matched) echo "max_clones=20 sigma_px=0.5" ;;
  *) echo "unknown OpenVINS variant $1" >&2; exit 2 ;;
  esac
}
