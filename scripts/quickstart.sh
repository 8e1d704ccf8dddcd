#!/usr/bin/env bash
# The main job on a quickly generated default: install what is missing, build, render a 20 s EuRoC-format sample
# along the simulator's built-in flight (constant +10 ms camera-IMU offset), run the filter on it in the
# state-relevant mode (t_d estimated), and print the trajectory's APE and the t_d estimate. The run is also written as
# an MCAP file to open in Foxglove (run_sr.mcap: images with features, poses, paths, t_d and its sigma; docs/bags.md).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
OUT=${OUT:-out/quickstart}
mkdir -p "$OUT"
if [ ! -f "$OUT/sample/mav0/cam0/data.csv" ]; then
  echo "== rendering the sample (20 s, 752x480, seed 1) into $OUT/sample =="
  build/ovton simulate --builtin --duration-s 20 --td0-ms 10 --seed 1 --out "$OUT/sample" -q
fi
echo "== ovton run --td-mode sr on $OUT/sample =="
build/ovton run --config config/sim/estimator_config.yaml --dataset "$OUT/sample" --td-mode sr \
  --output "$OUT/traj_sr.csv" --residual-log "$OUT/residuals_sr.csv" --mcap-out "$OUT/run_sr.mcap" -q
echo "== ovton eval (against the sample's ground truth and true offset) =="
build/ovton eval --est "$OUT/traj_sr.csv" --gt "$OUT/sample/mav0/state_groundtruth_estimate0/data.csv" \
  --td-truth "$OUT/sample/mav0/td_truth/data.csv" --json "$OUT/eval_sr.json"
