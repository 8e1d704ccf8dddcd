#!/usr/bin/env bash
# The errors-in-variables bias of the image-plane modes (time_offset.velocity_debias, docs/ton.md "Errors in
# variables"): feature-level simulations of V1_03_difficult (1 px independent pixel noise, the folders' own truth)
# with a constant +10 ms offset and with the worked case's drift (10 ms, +0.5 ms/s, 0.1 ms/sqrt(s)), SEEDS seeds
# each, DURATION_S s from 5 s; modes sir, tpn, ton (and sr for reference) with the correction off (0) and at the
# value these folders' noise calls for (1). Per mode and setting, means over seeds of: t_d error mean over the first
# 5 s and after it [ms] (the bias), t_d RMSE after 5 s, t_d NEES, TPE [mm], APE [mm].
# Usage: scripts/experiments/velocity_debias.sh [OUT] [SEEDS] [DURATION_S]   (~10 min for 4 seeds of 30 s)
#   OVTON_BIN overrides the binary, PYTHON the interpreter (needs numpy), SET adds config overrides to every run
#   (e.g. SET="ton.tpn_label_images=10"). Needs ../shared/data. Runs already in OUT
#   are kept. Writes OUT/summary.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/velocity_debias}
SEEDS=${2:-4}
DUR=${3:-30}
BIN=${OVTON_BIN:-build/ovton}
PY=${PYTHON:-python3}
[ -x "$BIN" ] || scripts/build.sh
GT=../shared/data/euroc_groundtruth/V1_03_difficult.txt
[ -f "$GT" ] || { echo "velocity_debias.sh needs $GT (../shared/data)" >&2; exit 2; }
mkdir -p "$OUT"
: >"$OUT/runs.txt"
for k in 0 1; do
  # Feature-level folders carry 1 px of independent noise: weighted and gated as such (as ton_defaults.sh part 2).
  python3 scripts/config_override.py config/sim/estimator_config.yaml "$OUT/k$k.yaml" update.sigma_px=1.0 \
    update.chi2_multiplier=1 slam.sigma_px=0 slam.chi2_multiplier=1 time_offset.velocity_debias=$k ${SET:-} >/dev/null
done
for kind in const drift; do
  args="--td0-ms 10"
  [ $kind = drift ] && args="--td-model drift --td0-ms 10 --td-bias-ms-per-s 0.5 --td-noise-ms-per-sqrt-s 0.1"
  for s in $(seq 1 "$SEEDS"); do
    d="$OUT/data/${kind}_s$s"
    [ -f "$d/sim.yaml" ] || "$BIN" simulate --gt "$GT" --start-s 5 --duration-s "$DUR" $args --seed "$s" \
      --features-only --out "$d" --force -q >/dev/null
    for mode in sr sir tpn ton; do
      for k in 0 1; do
        [ $mode = sr ] && [ $k = 1 ] && continue # no image-plane rows: nothing to correct
        est="$OUT/runs/${kind}_s${s}_${mode}_k$k.csv"
        mkdir -p "$OUT/runs"
        status=ok
        if [ -f "${est%.csv}.log" ] && grep -q '^trajectory:' "${est%.csv}.log"; then
          echo "$kind $s $mode $k $status $est $d" >>"$OUT/runs.txt"
          continue
        fi
        nice "$BIN" run --dataset "$d" --config "$OUT/k$k.yaml" --td-mode $mode --output "$est" -q --no-prefetch \
          >"${est%.csv}.log" 2>&1 || status=stopped
        echo "$kind $s $mode $k $status $est $d" >>"$OUT/runs.txt"
      done
    done
  done
done

"$PY" - "$OUT" "$SEEDS" "$DUR" "$(git rev-parse --short HEAD)" "${SET:-}" >"$OUT/summary.md" <<'PY'
import collections, re, sys
import numpy as np
out, seeds, dur, commit, extra = sys.argv[1:6]
acc = collections.defaultdict(list)
for line in open(f"{out}/runs.txt"):
    kind, seed, mode, k, status, est, d = line.split()
    log = open(est[:-4] + ".log").read()
    if status != "ok":
        acc[(kind, mode, k)].append(None)
        continue
    e = np.genfromtxt(est, delimiter=",", names=True)
    tru = np.genfromtxt(d + "/mav0/td_truth/data.csv", delimiter=",", comments="#")
    t = e["timestamp_ns"].astype(float)
    err = (e["td_s"] - np.interp(t, tru[:, 0], tru[:, 1])) * 1e3
    sig = e["td_sigma_s"] * 1e3
    ts = (t - t[0]) * 1e-9
    early, late = ts < 5, ts >= 5
    ape = float(re.search(r"APE ([0-9.]+) m", log).group(1)) * 1e3
    tpe = float(re.search(r"TPE ([0-9.]+) mm", log).group(1))
    acc[(kind, mode, k)].append((err[early].mean(), err[late].mean(), np.sqrt((err[late] ** 2).mean()),
                                 np.mean((err / sig) ** 2), tpe, ape))
print(f"# Errors in variables: the image-plane modes with and without `time_offset.velocity_debias`\n")
print(f"Made by `scripts/experiments/velocity_debias.sh {out} {seeds} {dur}` (commit {commit}): feature-level "
      f"V1_03_difficult, {dur} s from 5 s, 1 px independent noise, seeds 1-{seeds}; means over seeds"
      + (f"; every run with {extra}" if extra else "") + ".\n")
print("| offset | mode | velocity_debias | runs (stopped) | t_d error, first 5 s [ms] | t_d error after 5 s [ms] "
      "| t_d RMSE after 5 s [ms] | t_d NEES | TPE [mm] | APE [mm] |")
print("|---|---|---:|---|---:|---:|---:|---:|---:|---:|")
for (kind, mode, k), v in acc.items():
    ok = [x for x in v if x is not None]
    m = np.mean(ok, axis=0) if ok else [float("nan")] * 6
    print(f"| {kind} | {mode} | {k} | {len(v)} ({len(v) - len(ok)}) | {m[0]:+.2f} | {m[1]:+.2f} | {m[2]:.2f} | "
          f"{m[3]:.2f} | {m[4]:.2f} | {m[5]:.1f} |")
PY
cat "$OUT/summary.md"
