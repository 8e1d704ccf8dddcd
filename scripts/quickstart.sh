#!/usr/bin/env bash
# The main job on the bundled default: install what is missing, build, load the bundled sample and evaluate.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
OUT=${OUT:-out/quickstart}
mkdir -p "$OUT"
echo "== dataset =="
build/ovton info --dataset datasets/scube_sample
echo "== evaluation pipeline check: ground truth against itself (the filter lands with issue #4) =="
build/ovton eval --est datasets/scube_sample/groundtruth/data.csv --gt datasets/scube_sample/groundtruth/data.csv \
  --align posyaw --json "$OUT/eval.json"
