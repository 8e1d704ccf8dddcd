#!/usr/bin/env bash
# From a fresh clone to a comparison that shows what a time-offset model is for (docs/quickstart.md):
#  1. installs what the `ovton` binary needs (scripts/install_deps.sh --minimal: OpenCV's modules, not libopencv-dev);
#  2. builds only `ovton` (Ninja, precompiled headers, ccache when present; the tests are scripts/test.sh's job);
#  3. renders a 20 s flight (the built-in agile one, realistic images and IMU) whose camera-IMU offset starts at +10 ms
#     and drifts by 0.5 ms/s, so that t_d is observable and changes;
#  4. runs `ovton compare` with sr (constant offset, with its model check), ton (TON: TPN + FVON), drift (offset and its
#     rate in the state) and oracle (given the true offset), and sr with the check off (OpenVINS' constant offset) as
#     the baseline; prints the table, where the plots are, and what the numbers say;
#  5. writes the ton run as an MCAP file to open in Foxglove (run_ton.mcap: images with features, poses, paths, t_d and
#     its sigma; docs/bags.md).
# Usage: scripts/quickstart.sh   (OUT=folder for the results, default out/quickstart; JOBS=build jobs)
set -euo pipefail
cd "$(dirname "$0")/.."
T0=$SECONDS
scripts/install_deps.sh --minimal
T1=$SECONDS
# Ninja where present and the build folder is new (an existing folder keeps its generator; scripts/build.sh and
# scripts/test.sh reuse either): it compiles a library's files while the ones it depends on are still being built.
GENERATOR=()
if command -v ninja >/dev/null && [ ! -f build/CMakeCache.txt ]; then
  GENERATOR=(-G Ninja)
fi
cmake -S . -B build "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE=Release -DOVTON_PCH=ON >/dev/null
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
  --out "$OUT/compare" 2>&1 | tee "$OUT/compare.log"
# The baseline: sr as OpenVINS models t_d, a constant, without the model check that switches a contradicted constant
# to the drift state (docs/robustness.md, "The model check").
sed '/^time_offset:/a\  model_check: false' config/sim/estimator_config.yaml >"$OUT/sr_constant.yaml"
build/ovton run --config "$OUT/sr_constant.yaml" --dataset "$SAMPLE" --td-mode sr --output "$OUT/traj_sr_constant.csv" \
  -q >"$OUT/run_sr_constant.log"
build/ovton run --config config/sim/estimator_config.yaml --dataset "$SAMPLE" --td-mode ton \
  --output "$OUT/traj_ton.csv" --mcap-out "$OUT/run_ton.mcap" -q >"$OUT/run_ton.log"
T4=$SECONDS
echo
echo "t_d over time (truth and every mode): $OUT/compare/td.png   (also ape.png, top.png, results.md there)"
echo "the ton run for Foxglove (images, tracks, poses, t_d +- sigma): $OUT/run_ton.mcap"
# What the numbers just written say (results.csv, the runs' logs, the render's truth), not a template of expected ones.
truth_ms=$(awk -F, 'END { printf "%.3f", $2 * 1000 }' "$SAMPLE/mav0/td_truth/data.csv")
read -r c_td c_sigma c_nees c_tpe < <(awk '
  /^final t_d/ { td = $3; sigma = $6 } # final t_d 14.643 ms (sigma 0.414 ms)
  /^NEES/ { for (i = 1; i < NF; ++i) if ($i == "t_d") nees = $(i + 1) }
  /TPE/ { tpe = $(NF - 1) }
  END { print td, sigma, nees, tpe }' "$OUT/run_sr_constant.log")
switch_of() { # the IMU time at which a mode's model check switched, or nothing
  sed -n "s/^compare: $1: t_d model check: switched to the drift state at \([0-9.]*\) s.*/\1/p" "$OUT/compare.log" |
    head -1
}
sr_switch=$(switch_of sr)
ton_switch=$(switch_of ton)
awk -F, -v truth="$truth_ms" -v ctd="$c_td" -v csig="$c_sigma" -v cnees="$c_nees" -v ctpe="$c_tpe" \
  -v srsw="$sr_switch" -v tonsw="$ton_switch" 'NR > 1 { ape[$1] = $3 * 1000; tpe[$1] = $5; err[$1] = $12; fin[$1] = $7 }
  END {
    d = ctd - truth
    side = "ahead"
    if (d < 0) { d = -d; side = "behind" }
    printf "- a constant t_d (sr, model check off; OpenVINS'"'"' model): final %.2f +- %.2f ms for a truth of %.2f ms," \
           " %.1f sigma %s (t_d NEES %s), TPE %s mm.\n", ctd, csig, truth, d / csig, side, cnees, ctpe
    printf "- sr as shipped: %s; final %.2f ms, TPE %.2f mm.\n",
           srsw == "" ? "its model check did not fire" : sprintf("its model check saw t_d move and switched to the drift state at %.1f s", srsw),
           fin["sr"], tpe["sr"]
    printf "- ton (TPN + FVON%s) and drift (t_d and its rate in the state): t_d error %.2f / %.2f ms RMS, TPE %.2f / %.2f mm.\n",
           tonsw == "" ? "" : sprintf(", switched to the drift state at %.1f s", tonsw), err["ton"], err["drift"], tpe["ton"],
           tpe["drift"]
    printf "- oracle is told the true offset: APE %.1f mm is what a perfect t_d gives here (sr %.1f, ton %.1f, drift %.1f mm).\n",
           ape["oracle"], ape["sr"], ape["ton"], ape["drift"]
  }' "$OUT/compare/results.csv"
echo "(TPE = t_d error x speed, the position error the offset alone causes; APE = position error after alignment.)"
echo "quickstart: install $((T1 - T0)) s, build $((T2 - T1)) s, render $((T3 - T2)) s, compare and MCAP $((T4 - T3)) s;" \
  "total $((SECONDS - T0)) s"
