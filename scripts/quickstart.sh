#!/usr/bin/env bash
# From a fresh clone to a comparison that shows what a time-offset model is for (docs/quickstart.md):
#  1. installs what the `ovton` binary needs (scripts/install_deps.sh --minimal: OpenCV's modules, not libopencv-dev);
#  2. builds only `ovton` (ccache when present; the tests are scripts/test.sh's job);
#  3. renders a 20 s flight (the built-in agile one, realistic images and IMU) whose camera-IMU offset starts at +10 ms
#     and drifts by 0.5 ms/s, so that t_d is observable and changes;
#  4. runs `ovton compare` with sr (constant offset), ton (TON: TPN + FVON), drift (offset and its rate in the state)
#     and oracle (given the true offset), and prints the table, where the plots are, and what the numbers say;
#  5. writes the ton run as an MCAP file to open in Foxglove (run_ton.mcap: images with features, poses, paths, t_d and
#     its sigma; docs/bags.md).
# Usage: scripts/quickstart.sh   (OUT=folder for the results, default out/quickstart; JOBS=build jobs)
set -euo pipefail
cd "$(dirname "$0")/.."
T0=$SECONDS
scripts/install_deps.sh --minimal
T1=$SECONDS
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"${JOBS:-$(nproc)}" --target ovton
T2=$SECONDS
OUT=${OUT:-out/quickstart}
SAMPLE="$OUT/sample"
mkdir -p "$OUT"
if [ ! -f "$SAMPLE/mav0/cam0/data.csv" ]; then
  echo "== rendering the sample: 20 s, 752x480, t_d 10 ms drifting +0.5 ms/s, seed 1, into $SAMPLE =="
  build/ovton simulate --builtin --agility 1 --duration-s 20 --td-model drift --td0-ms 10 --td-bias-ms-per-s 0.5 \
    --seed 1 --out "$SAMPLE" -q
fi
T3=$SECONDS
echo "== ovton compare --modes sr,ton,drift,oracle on $SAMPLE =="
build/ovton compare --dataset "$SAMPLE" --config config/sim/estimator_config.yaml --modes sr,ton,drift,oracle \
  --out "$OUT/compare"
build/ovton run --config config/sim/estimator_config.yaml --dataset "$SAMPLE" --td-mode ton \
  --output "$OUT/traj_ton.csv" --mcap-out "$OUT/run_ton.mcap" -q >"$OUT/run_ton.log"
T4=$SECONDS
echo
echo "t_d over time (truth and every mode): $OUT/compare/td.png   (also ape.png, top.png, results.md there)"
echo "the ton run for Foxglove (images, tracks, poses, t_d +- sigma): $OUT/run_ton.mcap"
# Three lines from the numbers just written (results.csv), not from a template of expected ones.
awk -F, 'NR > 1 { ape[$1] = $3 * 1000; tpe[$1] = $5; err[$1] = $12; fin[$1] = $7 }
  END {
    printf "- sr models t_d as a constant: it trails the drifting offset (t_d error %.2f ms RMS, TPE %.2f mm).\n",
           err["sr"], tpe["sr"]
    printf "- ton and drift model how t_d changes: t_d error %.2f / %.2f ms, TPE %.2f / %.2f mm (sr: %.2f mm).\n",
           err["ton"], err["drift"], tpe["ton"], tpe["drift"], tpe["sr"]
    printf "- oracle is told the true offset: its APE %.1f mm is what a perfect t_d gives here (sr %.1f, ton %.1f, drift %.1f mm).\n",
           ape["oracle"], ape["sr"], ape["ton"], ape["drift"]
  }' "$OUT/compare/results.csv"
echo "(TPE = t_d error x speed, the position error the offset alone causes; APE = position error after alignment.)"
echo "quickstart: install $((T1 - T0)) s, build $((T2 - T1)) s, render $((T3 - T2)) s, compare and MCAP $((T4 - T3)) s;" \
  "total $((SECONDS - T0)) s"
