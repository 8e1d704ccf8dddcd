#!/usr/bin/env bash
# The measurements behind FilterHealth's thresholds (docs/robustness.md): healthy and diverged runs watched to their end
# (--health-checks off --td-search off), per second the features accepted / gated / failing triangulation (from the
# residual log's status column), and the largest 2-s step of t̂_d (> 2 ms) in units of what its covariance allowed.
# Usage: nice -n 10 scripts/experiments/health_evidence.sh [OUT] [RENDERED_FOLDER]
#   RENDERED_FOLDER: a rendered V1_02 flight (as td_robustness.sh makes: simulate --gt V1_02_medium.txt --start-s 5
#   --duration-s 25 --td0-ms 10 --seed 1); made in OUT when not given. ~10 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/health_evidence}
BIN=${BIN:-build/ovton}
[ -x "$BIN" ] || scripts/build.sh
COMMIT=$(git rev-parse --short HEAD)
mkdir -p "$OUT"
V102=${2:-$OUT/data_V1_02_medium}
[ -d "$V102/mav0" ] || "$BIN" simulate --out "$V102" --gt ../shared/data/euroc_groundtruth/V1_02_medium.txt --start-s 5 \
  --duration-s 25 --td0-ms 10 --seed 1 -q
FEAT="$OUT/data_builtin_features"
[ -d "$FEAT/mav0" ] || "$BIN" simulate --out "$FEAT" --builtin --duration-s 8 --features-only --seed 11 --td0-ms 10 -q

# label folder config mode td_init_ms [extra]
one() {
  "$BIN" run --dataset "$2" --config "config/$3/estimator_config.yaml" --health-checks off --td-search off \
    --td-mode "$4" --td-init-ms "$5" ${6:-} \
    --output "$OUT/$1.csv" --residual-log "$OUT/$1_res.csv" -q >"$OUT/$1.log" 2>&1 || echo "$1: exit $?" >>"$OUT/$1.log"
}
one v102_sr_10 "$V102" sim sr 10
one v102_sr_50 "$V102" sim sr 50
one v102_sr_160 "$V102" sim sr 160
one v102_sr_110 "$V102" sim sr 110
for m in sir fvon ton sr; do one "builtin_${m}_0" "$FEAT" euroc_mav "$m" 0 "--init groundtruth"; done
for m in sr sir ton; do
  one "moving_$m" ../shared/data/euroc_v1_01_moving euroc_mav "$m" 0 "--init groundtruth"
done
one micro_sr ../shared/data/euroc_v1_01_micro euroc_mav sr 0

python3 - "$OUT" "$COMMIT" <<'PY' | tee "$OUT/table.md"
import csv, math, os, sys
out, commit = sys.argv[1], sys.argv[2]
print(f"Made by `scripts/experiments/health_evidence.sh` at commit {commit} (health checks off, no t_d search).\n")
print("| run | per second: accepted / gated / triangulation failed (min-max over the run) | gate rate | "
      "worst 2-s t_d step > 2 ms [σ] | final t̂_d ± σ [ms] |")
print("|---|---|---|---|---|")
names = ["v102_sr_10", "v102_sr_50", "v102_sr_160", "v102_sr_110", "builtin_sir_0", "builtin_fvon_0", "builtin_ton_0",
         "builtin_sr_0", "moving_sr", "moving_sir", "moving_ton", "micro_sr"]
for name in names:
    res, traj = f"{out}/{name}_res.csv", f"{out}/{name}.csv"
    per_s = {}
    if os.path.exists(res):
        seen, t0 = {}, None
        for r in csv.DictReader(open(res)):
            seen[(r["update_id"], r["feature_id"])] = (int(r["t_cam_ns"]), int(r["status"]))
        for t, st in seen.values():
            t0 = t if t0 is None else min(t0, t)
        for t, st in seen.values():
            per_s.setdefault(int((t - t0) * 1e-9), [0, 0, 0])[st] += 1
    def span(k):
        v = [c[k] for c in per_s.values()]
        return f"{min(v)}-{max(v)}" if v else "-"
    rates = [c[1] / (c[0] + c[1]) for c in per_s.values() if c[0] + c[1] > 0]
    gate = f"{100 * min(rates):.0f}-{100 * max(rates):.0f} %" if rates else "-"
    rows = list(csv.DictReader(open(traj))) if os.path.exists(traj) else []
    worst, j = None, 0
    t = [int(r["timestamp_ns"]) * 1e-9 for r in rows]
    td = [float(r["td_s"]) for r in rows]
    sg = [float(r["td_sigma_s"]) for r in rows]
    for k in range(len(t)):
        while t[k] - t[j] > 2.0:
            j += 1
        d = abs(td[k] - td[j])
        if t[k] - t[j] >= 1.8 and d > 2e-3:
            z = d / math.sqrt(max(sg[j] ** 2 - sg[k] ** 2, 1e-18))
            worst = z if worst is None else max(worst, z)
    final = f"{td[-1] * 1e3:.2f} ± {sg[-1] * 1e3:.2f}" if rows else "-"
    print(f"| {name} | {span(0)} / {span(1)} / {span(2)} | {gate} | "
          f"{'-' if worst is None else f'{worst:.1f}'} | {final} |")
PY
