#!/usr/bin/env bash
# Issue 37's two missing items on the real phone recording (../shared/data/android_phone_walk: 52 s, no calibration,
# no ground truth), docs/calibrate.md "diagnose on the phone run" and "OpenVINS with the same calibration":
#   1. `ovton calibrate --out OUT/cal`, `ovton run` (sr, drift) with --residual-log, `ovton diagnose` on each log;
#   2. OpenVINS (scripts/peer/ov_euroc_harness.cpp, built against OV_ROOT outside the repository) on the same folder
#      with calibrate's OUT/cal/kalibr/camchain-imucam.yaml (init=ov: OpenVINS's own initialiser, no ground truth),
#      its initial t_d the calibrated one and 0; ovton timed the peer script's way (-q --no-prefetch, one thread);
#      a table of path length, z range, end position, final t_d, CPU (user + sys), and each trajectory against
#      ovton sr's (and OpenVINS default's) by `ovton eval` (posyaw, se3, sim3's scale): no ground truth exists, so
#      these are agreements between systems, not errors.
#
# Usage: OV_ROOT=DIR scripts/experiments/phone_peer.sh [--bin FILE] [--out DIR] [--repeats N] [--skip-calibrate]
#   OV_ROOT         an OpenVINS source tree with its ov_msckf_lib built in OV_ROOT/build (openvins_vs_ovton.sh)
#   --bin FILE      the ovton binary (default build/ovton)
#   --out DIR       everything goes here (default /tmp/phone37)
#   --repeats N     timed runs per system variant, alternating; CPU is the median (default 3)
#   --skip-calibrate  keep OUT/cal and the residual-log runs and diagnoses already there
#   --summary-only  only rewrite OUT/summary.md from the runs already in OUT
# The harness is built in OUT/peer_build with `nice -n 10 make -j1` under `flock /work/.build.lock` when that file
# exists. Every run is `nice -n 10`, one at a time. Writes OUT/summary.md.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../.." && pwd)
# shellcheck source=scripts/peer/peer_common.sh
. "$REPO/scripts/peer/peer_common.sh"
DATA=$REPO/../shared/data/android_phone_walk
BIN=$REPO/build/ovton
OUT=/tmp/phone37
REPEATS=3
SKIP_CAL=0
SUMMARY_ONLY=0
while [ $# -gt 0 ]; do
  case "$1" in
  --bin) BIN=$(realpath "$2"); shift 2 ;;
  --out) OUT=$2; shift 2 ;;
  --repeats) REPEATS=$2; shift 2 ;;
  --skip-calibrate) SKIP_CAL=1; shift ;;
  --summary-only) SUMMARY_ONLY=1; shift ;;
  -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  *) echo "unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
: "${OV_ROOT:?set OV_ROOT to an OpenVINS source tree with build/libov_msckf_lib.so}"
OV_ROOT=$(realpath "$OV_ROOT")
[ -f "$OV_ROOT/build/libov_msckf_lib.so" ] || { echo "no $OV_ROOT/build/libov_msckf_lib.so" >&2; exit 2; }
[ -x "$BIN" ] || { echo "no ovton binary at $BIN (--bin)" >&2; exit 2; }
[ -d "$DATA/mav0" ] || { echo "no $DATA" >&2; exit 2; }
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
cd "$OUT"
N() { nice -n 10 "$@"; }
T() { local t=$1; shift; nice -n 10 /usr/bin/time -f "%e %U %S" -o "$t" "$@"; } # wall user sys

# ---- 1. calibrate, run with residual logs, diagnose
if [ "$SUMMARY_ONLY" = 1 ]; then SKIP_CAL=1; fi
if [ "$SKIP_CAL" = 0 ]; then
  rm -rf cal
  T calibrate.time "$BIN" calibrate -d "$DATA" --out cal > calibrate.log 2>&1
  for m in sr drift; do
    T "ovton_${m}_res.time" "$BIN" run -d cal -c cal/ovton_config.yaml -m "$m" --residual-log "${m}_res.csv" \
      -o "ovton_${m}_res_traj.csv" > "ovton_${m}_res.log" 2>&1
    rm -rf "diag_$m"
    T "diag_$m.time" "$BIN" diagnose --log "${m}_res.csv" --dataset cal --out "diag_$m" > "diag_$m.log" 2>&1
  done
  # diagnose -> model -> re-run: sr with the readout fixed at the filter's last value plus diagnose's correction
  # (when diagnose named rolling_shutter), then diagnose again
  RF=$(python3 - <<'PY'
import csv, json
j = json.load(open("diag_sr/diagnose.json"))
c = [c for c in j["candidates"] if c["key"] == "rolling_shutter" and c["explained"]]
r = float(list(csv.DictReader(open("sr_res_calib.csv")))[-1]["readout_s"])
print(f"{r + c[0]['estimates'][0]['value'] * 1e-3:.4f}" if c else "")
PY
)
  if [ -n "$RF" ]; then
    sed "s/^  readout: true/  readout: false/; s/^  readout_s: .*/  readout_s: $RF/" cal/ovton_config.yaml > cfg_rf.yaml
    T ovton_rf_res.time "$BIN" run -d cal -c cfg_rf.yaml -m sr --residual-log rf_res.csv -o ovton_rf_res_traj.csv \
      > ovton_rf_res.log 2>&1
    rm -rf diag_rf
    T diag_rf.time "$BIN" diagnose --log rf_res.csv --dataset cal --out diag_rf > diag_rf.log 2>&1
  fi
fi

TD_CAL=$(sed -n 's/^ *timeshift_cam_imu: *//p' cal/kalibr/camchain-imucam.yaml)
if [ "$SUMMARY_ONLY" = 0 ]; then
# ---- 2. the harness (our copy, scripts/peer), outside the repository
LOCK=()
[ -e /work/.build.lock ] && LOCK=(flock /work/.build.lock)
build_peer_harness "$OV_ROOT" "$OUT/peer_build" 1 "${LOCK[@]}"
H=$OUT/peer_build/ov_euroc_harness

# ---- 3. timed runs, alternating: ovton (the peer script's flags) and OpenVINS's variants
#   default = OpenVINS's own EuRoC choice (50 SLAM features, online extrinsics and intrinsics: the closest to
#   ovton's written config, which also estimates intrinsics, extrinsics and readout); noslam = the harness default
declare -A OVARGS=(
  [default_tdcal]="$(ov_args default)"
  [default_td0]="$(ov_args default) td0=0"
  [noslam_tdcal]="$(ov_args noslam)"
  [noslam_td0]="$(ov_args noslam) td0=0"
)
OVV=(default_tdcal default_td0 noslam_tdcal noslam_td0)
mkdir -p runs
for rep in $(seq 1 "$REPEATS"); do
  for m in sr drift; do
    OPENCV_FOR_THREADS_NUM=1 T "runs/ovton_${m}_r$rep.time" "$BIN" run -q --no-prefetch -d cal \
      -c cal/ovton_config.yaml -m "$m" -o "runs/ovton_${m}_r$rep.csv" > "runs/ovton_${m}_r$rep.log" 2>&1 ||
      echo "ovton $m failed (runs/ovton_${m}_r$rep.log)" >&2
  done
  for v in "${OVV[@]}"; do
    # shellcheck disable=SC2086
    OV_ROOT=$OV_ROOT T "runs/ov_${v}_r$rep.time" "$H" cal "runs/ov_${v}_r$rep" threads=1 init=ov \
      camchain=cal/kalibr/camchain-imucam.yaml ${OVARGS[$v]} > "runs/ov_${v}_r$rep.log" 2>&1 ||
      echo "OpenVINS $v failed (runs/ov_${v}_r$rep.log)" >&2
    [ -f "runs/ov_${v}_r$rep.csv" ] && cut -d, -f1-19 "runs/ov_${v}_r$rep.csv" > "runs/ov_${v}_r$rep.est.csv"
  done
done

# ---- 4. agreement between trajectories (first repeat's; `ovton eval`, one as the reference)
REF_A=runs/ovton_sr_r1.csv
REF_B=runs/ov_default_tdcal_r1.est.csv
for est in runs/ovton_drift_r1.csv runs/ov_*_r1.est.csv ovton_sr_res_traj.csv ovton_rf_res_traj.csv; do
  [ -f "$est" ] || continue
  for a in posyaw se3 sim3; do
    "$BIN" eval --est "$est" --gt "$REF_A" --align "$a" --json "$est.vs_sr.$a.json" > /dev/null 2>&1 || true
  done
done
for est in runs/ovton_sr_r1.csv runs/ov_*_r1.est.csv; do
  [ "$est" = "$REF_B" ] && continue
  "$BIN" eval --est "$est" --gt "$REF_B" --align posyaw --json "$est.vs_ovdef.posyaw.json" > /dev/null 2>&1 || true
done

fi # SUMMARY_ONLY

# ---- 5. the table
python3 - "$OUT" "$REPEATS" "$TD_CAL" "$(git -C "$REPO" rev-parse --short HEAD)" "$BIN" \
  "$(uptime | sed 's/.*load average: //')" > summary.md <<'PY'
import csv, json, math, os, re, statistics as st, sys
out, reps, td_cal, commit, binp, load = sys.argv[1:7]
reps = int(reps)
os.chdir(out)
def traj(f):
    rows = list(csv.DictReader(open(f)))
    P = [(float(r["px"]), float(r["py"]), float(r["pz"])) for r in rows]
    L = sum(math.dist(P[i], P[i + 1]) for i in range(len(P) - 1))
    z = [p[2] - P[0][2] for p in P]
    e = tuple(a - b for a, b in zip(P[-1], P[0]))
    return dict(n=len(rows), t0=int(rows[0]["timestamp_ns"]), span=(int(rows[-1]["timestamp_ns"]) -
                int(rows[0]["timestamp_ns"])) * 1e-9, L=L, zmin=min(z), zmax=max(z), end=e,
                td=float(rows[-1]["td_s"]) * 1e3, tds=float(rows[-1]["td_sigma_s"]) * 1e3)
def cpu(pre):
    xs = []
    for r in range(1, reps + 1):
        f = f"{pre}_r{r}.time"
        if os.path.exists(f):
            w = open(f).read().split()
            try:
                xs.append(float(w[-2]) + float(w[-1]))
            except (ValueError, IndexError):
                pass
    return (st.median(xs), min(xs), max(xs)) if xs else None
def ev(f):
    try:
        j = json.load(open(f))
        return j
    except Exception:
        return None
first = min(traj("runs/ovton_sr_r1.csv")["t0"], traj("runs/ov_default_tdcal_r1.est.csv")["t0"]
            if os.path.exists("runs/ov_default_tdcal_r1.est.csv") else 10**20)
L = [f"Commit {commit}, binary {binp}, {reps} timed run(s) per row (CPU: median, min-max, user + sys), "
     f"load average at the end: {load}. Calibrated t_d {float(td_cal) * 1e3:.2f} ms.", "",
     "| system | variant | initial t_d [ms] | first row [s] | path [m] | z range [m] | end − start [m] | "
     "final t_d [ms] | CPU [s] | vs ovton sr: APE posyaw / se3 [m], ARE posyaw [deg], sim3 scale | "
     "vs OpenVINS default: APE posyaw [m] |", "|---|---|---:|---:|---:|---|---|---|---|---|---:|"]
rows = [("ovton", "sr", "runs/ovton_sr_r1.csv", "runs/ovton_sr", td_cal),
        ("ovton", "drift", "runs/ovton_drift_r1.csv", "runs/ovton_drift", td_cal)]
for v in ("default_tdcal", "default_td0", "noslam_tdcal", "noslam_td0"):
    rows.append(("OpenVINS", v, f"runs/ov_{v}_r1.est.csv", f"runs/ov_{v}", "0" if v.endswith("td0") else td_cal))
for sysn, var, f, pre, td0 in rows:
    if not os.path.exists(f) or os.path.getsize(f) < 100:
        L.append(f"| {sysn} | {var} | {float(td0) * 1e3:.2f} | – | failed | | | | | | |")
        continue
    t = traj(f); c = cpu(pre)
    a = {k: ev(f"{f}.vs_sr.{k}.json") for k in ("posyaw", "se3", "sim3")}
    b = ev(f"{f}.vs_ovdef.posyaw.json")
    vs = "reference" if f == "runs/ovton_sr_r1.csv" else (
        f"{a['posyaw']['ape_rmse_m']:.2f} / {a['se3']['ape_rmse_m']:.2f}, {a['posyaw']['are_rmse_deg']:.1f}, "
        f"{a['sim3']['align_scale']:.3f}" if all(a.values()) else "–")
    vb = "reference" if var == "default_tdcal" else (f"{b['ape_rmse_m']:.2f}" if b else "–")
    e = t["end"]
    L.append(f"| {sysn} | {var} | {float(td0) * 1e3:.2f} | {(t['t0'] - first) * 1e-9:.2f} | {t['L']:.1f} | "
             f"{t['zmin']:.2f} … {t['zmax']:.2f} | ({e[0]:.2f}, {e[1]:.2f}, {e[2]:.2f}) = {math.hypot(*e):.2f} | "
             f"{t['td']:.2f} ± {t['tds']:.2f} | " + (f"{c[0]:.1f} ({c[1]:.1f}-{c[2]:.1f})" if c else "–") +
             f" | {vs} | {vb} |")
L.append("")
L.append("The residual-log runs (`ovton run ... --residual-log`, not timed the same way):")
for m in ("sr", "drift", "rf"):
    if m == "rf" and os.path.exists("cfg_rf.yaml"):
        L.append("- rf: sr re-run with " + " and ".join(l.strip() for l in open("cfg_rf.yaml")
                                                       if l.strip().startswith(("readout:", "readout_s:"))))
    f = f"ovton_{m}_res_traj.csv"
    if os.path.exists(f):
        t = traj(f); e = t["end"]
        L.append(f"- {m}: path {t['L']:.1f} m, z {t['zmin']:.2f} … {t['zmax']:.2f} m, end − start ({e[0]:.2f}, "
                 f"{e[1]:.2f}, {e[2]:.2f}) m, final t_d {t['td']:.2f} ± {t['tds']:.2f} ms")
        a = ev(f"{f}.vs_sr.posyaw.json")
        if a and m != "sr":
            L.append(f"  - against the timed sr run (posyaw): APE {a['ape_rmse_m']:.3f} m, ARE {a['are_rmse_deg']:.2f} deg")
    log = f"ovton_{m}_res.log"
    if os.path.exists(log):
        for line in open(log):
            if line.startswith("t_d model check"):
                L.append(f"  - {line.strip()}")
    f = f"{m}_res_calib.csv"
    if os.path.exists(f):
        r = list(csv.DictReader(open(f)))[-1]
        L.append(f"  - filter's calibration at the end: f {float(r['intr_0']):.1f} / {float(r['intr_1']):.1f} px, "
                 f"c {float(r['intr_2']):.1f} / {float(r['intr_3']):.1f}, k1 {float(r['intr_4']):.3f}, "
                 f"k2 {float(r['intr_5']):.3f}, readout {float(r['readout_s']) * 1e3:.1f} ms, "
                 f"t_d {float(r['td_s']) * 1e3:.2f} ms")
    d = f"diag_{m}/diagnose.json"
    if os.path.exists(f"diag_{m}.log"):
        L.append(f"  - diagnose (diag_{m}.log):")
        for line in open(f"diag_{m}.log"):
            if re.match(r"^\s*\d+\s+\S+\s+(EXPLAINED|not explained|not testable)", line) or \
               re.match(r"^\s+by ", line):
                L.append("    " + line.rstrip())
for v in ("default_tdcal", "default_td0", "noslam_tdcal", "noslam_td0"):
    f = f"runs/ov_{v}_r1.log"
    if os.path.exists(f):
        m = [l[l.find("init=ov:"):].strip() for l in open(f) if "init=ov:" in l]
        if m:
            L.append(f"- OpenVINS {v}: {m[0]}")
# heading: OpenVINS default against ovton sr, yaw difference at the nearest ovton row (unwrapped), and gyro biases
def rows_q(f):
    R = list(csv.DictReader(open(f)))
    return [(int(r["timestamp_ns"]), [float(r[k]) for k in ("qw", "qx", "qy", "qz")],
             [float(r[k]) for k in ("bgx", "bgy", "bgz")]) for r in R]
def yaw(q):
    w, x, y, z = q
    return math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
A, B = "runs/ovton_sr_r1.csv", "runs/ov_default_tdcal_r1.est.csv"
if os.path.exists(A) and os.path.exists(B):
    import bisect
    a, b = rows_q(A), rows_q(B)
    ta = [r[0] for r in a]
    ts, ds, prev = [], [], None
    for t, q, _ in b:
        i = min(bisect.bisect_left(ta, t), len(a) - 1)
        d = yaw(a[i][1]) - yaw(q)
        if prev is not None:
            d += 360 * round((prev - d) / 360)
        prev = d
        ts.append((t - b[0][0]) * 1e-9); ds.append(d)
    n = len(ts); mt, md = sum(ts) / n, sum(ds) / n
    slope = sum((x - mt) * (y - md) for x, y in zip(ts, ds)) / sum((x - mt) ** 2 for x in ts)
    L.append(f"- heading, ovton sr − OpenVINS default (yaw about the world z, unaligned frames): {ds[0]:.1f} deg at "
             f"its first row, {ds[-1]:.1f} deg at its last ({ts[-1]:.1f} s later), least-squares slope "
             f"{slope:.3f} deg/s")
    for name, r in (("ovton sr", a), ("OpenVINS default", b)):
        mid, end = r[len(r) // 2][2], r[-1][2]
        L.append(f"- gyro bias {name}: mid-run ({mid[0]:.4f}, {mid[1]:.4f}, {mid[2]:.4f}), end ({end[0]:.4f}, "
                 f"{end[1]:.4f}, {end[2]:.4f}) rad/s")
print("\n".join(L))
PY
cat summary.md
