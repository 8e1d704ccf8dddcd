#!/usr/bin/env bash
# Is a change of APE between two binaries (or configs) on one folder a real difference or the spread of one run?
# Every cam0 pixel of FOLDER is moved by -1, 0 or +1 grey level (seeded, uniform; below any camera's own noise), SEEDS
# times; both binaries run `sr` mono on each dithered copy (the same images for both), and the APE (`ovton eval
# --align posyaw`) is printed per seed, as mean +- sd per binary, and as the paired difference B - A with its standard
# error. The dithered folders link everything but cam0's PNGs to FOLDER.
# Usage: scripts/experiments/pixel_dither.sh OUT FOLDER SEEDS BIN_A CONFIG_A BIN_B CONFIG_B
#   e.g. ... /tmp/pd /tmp/stereo9/v102c 10 /tmp/ovton_old old_config.yaml build/ovton config/sim/estimator_config.yaml
# (an older binary takes the config of its own commit: `git show COMMIT:config/sim/estimator_config.yaml`).
# docs/peer.md, "ovton's own APE since 5a2a39c", has what it gave for the tracker change of d2f43ac.
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -eq 7 ] || { sed -n 2,9p "$0" >&2; exit 2; }
OUT=$1 FOLDER=$2 SEEDS=$3 BIN_A=$4 CFG_A=$5 BIN_B=$6 CFG_B=$7
EVAL=${OVTON_EVAL:-build/ovton}
mkdir -p "$OUT"
DITHER=$OUT/dither
if [ ! -x "$DITHER" ]; then
  cat >"$OUT/dither.cpp" <<'EOF'
// dither SRC_DIR DST_DIR SEED: every pixel of every image in SRC_DIR +-1 grey level (or 0), seeded, PNG to DST_DIR
#include <opencv2/imgcodecs.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>
int main(int argc, char **argv) {
  namespace fs = std::filesystem;
  if (argc != 4)
    return 2;
  std::mt19937 rng(std::stoul(argv[3]));
  std::uniform_int_distribution<int> d(-1, 1);
  std::vector<fs::path> files;
  for (const auto &e : fs::directory_iterator(argv[1]))
    files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const auto &f : files) {
    cv::Mat m = cv::imread(f.string(), cv::IMREAD_GRAYSCALE);
    if (m.empty()) {
      std::fprintf(stderr, "cannot read %s\n", f.c_str());
      return 1;
    }
    for (int y = 0; y < m.rows; ++y) {
      unsigned char *p = m.ptr<unsigned char>(y);
      for (int x = 0; x < m.cols; ++x)
        p[x] = static_cast<unsigned char>(std::clamp(p[x] + d(rng), 0, 255));
    }
    cv::imwrite((fs::path(argv[2]) / f.filename()).replace_extension(".png").string(), m,
                {cv::IMWRITE_PNG_COMPRESSION, 1});
  }
  return 0;
}
EOF
  # shellcheck disable=SC2046
  g++ -O2 -std=c++17 "$OUT/dither.cpp" -o "$DITHER" $(pkg-config --cflags --libs opencv4)
fi
src=$(cd "$FOLDER" && pwd)/mav0
ape() { # BIN CONFIG FOLDER CSV -> APE [mm]
  OPENCV_FOR_THREADS_NUM=1 nice -n 10 "$1" run -q -c "$2" --dataset "$3" -m sr -o "$4" --no-prefetch >"$4.log" 2>&1
  "$EVAL" eval --est "$4" --gt "$3/mav0/state_groundtruth_estimate0/data.csv" --align posyaw --json "$4.json" >/dev/null
  python3 -c "import json,sys; print('%.2f' % (json.load(open(sys.argv[1]))['ape_rmse_m'] * 1e3))" "$4.json"
}
echo "seed,ape_a_mm,ape_b_mm" >"$OUT/ape.csv"
for s in $(seq 1 "$SEEDS"); do
  d=$OUT/s$s
  if [ ! -d "$d/mav0/cam0/data" ]; then
    mkdir -p "$d/mav0/cam0/data"
    for x in "$src"/*; do [ "$(basename "$x")" = cam0 ] || ln -sfn "$x" "$d/mav0/$(basename "$x")"; done
    for x in "$src"/cam0/*; do [ "$(basename "$x")" = data ] || ln -sfn "$x" "$d/mav0/cam0/$(basename "$x")"; done
    nice -n 10 "$DITHER" "$src/cam0/data" "$d/mav0/cam0/data" "$s"
  fi
  a=$(ape "$BIN_A" "$CFG_A" "$d" "$OUT/a_s$s.csv")
  b=$(ape "$BIN_B" "$CFG_B" "$d" "$OUT/b_s$s.csv")
  echo "$s,$a,$b" | tee -a "$OUT/ape.csv"
done
python3 - "$OUT/ape.csv" <<'EOF'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
a = [float(r['ape_a_mm']) for r in rows]; b = [float(r['ape_b_mm']) for r in rows]; d = [y - x for x, y in zip(a, b)]
def ms(v):
    m = sum(v) / len(v); s = math.sqrt(sum((x - m) ** 2 for x in v) / max(len(v) - 1, 1)); return m, s
for name, v in (('A', a), ('B', b)):
    m, s = ms(v); print(f'{name}: APE {m:.1f} +- {s:.1f} mm ({min(v):.1f}-{max(v):.1f}) over {len(v)} seeds')
m, s = ms(d)
print(f'B - A, same seed: {m:+.1f} +- {s:.1f} mm (standard error {s / math.sqrt(len(d)):.1f}); B worse on '
      f'{sum(x > 0 for x in d)} of {len(d)}')
EOF
