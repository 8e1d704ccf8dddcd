#!/usr/bin/env bash
# OpenVINS and ovton on the same EuRoC folders, scored by the same `ovton eval`, timed in the same run.
#
# Usage: OV_ROOT=DIR scripts/peer/openvins_vs_ovton.sh [options] FOLDER...
#   OV_ROOT              an OpenVINS source tree holding ov_core, ov_init, ov_msckf and config (rpng/open_vins; measured
#                        at 6948812). Its library is built in $OV_ROOT/build when missing. Nothing of it enters this repo.
#   --harness DIR        the shared harness source (default: ../shared/peer/openvins_harness next to the repository)
#   --build DIR          where the harness (and the track-exchange tool) are built (default /tmp/ovton_peer_build)
#   --out DIR            run folders, trajectories and tables (default /tmp/ovton_peer)
#   --ov-variants LIST   OpenVINS variants, comma separated (default noslam,default,matched):
#                          noslam  = harness defaults (11 clones, 1 px, no SLAM features, no online calibration)
#                          default = max_slam=50 calib_ext=1 calib_int=1 (OpenVINS's own EuRoC choice)
#                          matched = max_clones=20 sigma_px=0.5 (ovton's simulation config)
#                        VARIANT@imuK (e.g. matched@imu4) runs VARIANT on a view of the folder whose imu0/sensor.yaml
#                        noise densities and random walks are K times the folder's (as ovton's imu.noise_multiplier);
#                        VARIANT@imufit: the ADIS16448's measured values that config/euroc_mav declares instead;
#                        VARIANT@ptsN (e.g. noslam@pts400) gives OpenVINS num_pts=N (default 200; OpenVINS divides it by
#                        the number of cameras: 100 per camera in stereo)
#   --ovton-modes LIST   ovton modes (MODE[+PROCESS]), comma separated (default sr,drift)
#   --ovton-config-sim F / --ovton-config-real F
#                        ovton configs for simulated folders (those with mav0/td_truth) and real ones
#                        (default config/sim/estimator_config.yaml and config/euroc_mav/estimator_config.yaml; real
#                        folders also get --init groundtruth, as the harness initialises OpenVINS from ground truth)
#   --repeats N          runs per system and folder, alternating ovton and OpenVINS; CPU time is the median (default 1)
#   --stereo             also run both systems in stereo on folders with mav0/cam1 (issue 40): OpenVINS's variants
#                        with use_stereo=true, max_cameras=2 and cam1's calibration (scripts/peer/ov_euroc_harness.cpp,
#                        our copy of the shared harness, built in BUILD/peer; rows `VARIANT stereo`), ovton's modes with
#                        `--cameras 0,1` (rows `MODE stereo`). The mono rows stay (ovton with `--cameras 0` on such
#                        folders, OpenVINS through the shared harness), so stereo and mono are one run and one table;
#                        folders without cam1 get mono rows only. The table gains CPU per frame, CPU / OpenVINS noslam
#                        stereo, CIT and the time from which t_d stays within 1 ms, and a stereo summary
#   --exchange           also swap front ends: ovton's estimator on OpenVINS's tracks and OpenVINS's (matched)
#                        estimator on ovton's tracks (`ovton track`; builds scripts/peer/ov_track_exchange.cpp)
#   --md FILE            the Markdown table (default OUT/peer.md)
#   --resume             keep OUT/results.csv and skip the runs it already holds (an interrupted run goes on where it
#                        stopped; the table covers old and new rows)
#   --bin FILE           the ovton binary (default build/ovton)
# Every process runs under `nice -n 10`, one at a time. OpenVINS runs with one OpenCV thread (threads=1); ovton with
# `--no-prefetch`, which (since `ovton run --opencv-threads` exists) also turns OpenCV's pool off: before, Debian's
# TBB-backed pool ignored OPENCV_FOR_THREADS_NUM=1 (still set here for older binaries) and ran part of the tracker on
# a second core. So the CPU times compare one core against one core.
# ms/frame excludes the PNG decode on both sides: OpenVINS's feed_measurement_camera, ovton's tracking + propagation
# + update. CPU [s] is the whole process (user + sys), PNG decode and CSV parsing included.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../.." && pwd)
# shellcheck source=scripts/peer/peer_common.sh
. "$REPO/scripts/peer/peer_common.sh"
HARNESS=$REPO/../shared/peer/openvins_harness
BUILD=/tmp/ovton_peer_build
OUT=/tmp/ovton_peer
OV_VARIANTS=noslam,default,matched
OVTON_MODES=sr,drift
CFG_SIM=$REPO/config/sim/estimator_config.yaml
CFG_REAL=$REPO/config/euroc_mav/estimator_config.yaml
REPEATS=1
EXCHANGE=0
STEREO=0
RESUME=0
MD=
BIN=$REPO/build/ovton
FOLDERS=()
while [ $# -gt 0 ]; do
  case "$1" in
  --harness) HARNESS=$2; shift 2 ;;
  --build) BUILD=$2; shift 2 ;;
  --out) OUT=$2; shift 2 ;;
  --ov-variants) OV_VARIANTS=$2; shift 2 ;;
  --ovton-modes) OVTON_MODES=$2; shift 2 ;;
  --ovton-config-sim) CFG_SIM=$(realpath "$2"); shift 2 ;;
  --ovton-config-real) CFG_REAL=$(realpath "$2"); shift 2 ;;
  --repeats) REPEATS=$2; shift 2 ;;
  --exchange) EXCHANGE=1; shift ;;
  --stereo) STEREO=1; shift ;;
  --resume) RESUME=1; shift ;;
  --md) MD=$2; shift 2 ;;
  --bin) BIN=$(realpath "$2"); shift 2 ;;
  -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  -*) echo "unknown option $1 (see --help)" >&2; exit 2 ;;
  *) FOLDERS+=("$(realpath "$1")"); shift ;;
  esac
done
[ ${#FOLDERS[@]} -gt 0 ] || { echo "give at least one EuRoC folder (see --help)" >&2; exit 2; }
: "${OV_ROOT:?set OV_ROOT to an OpenVINS source tree (ov_core ov_init ov_msckf config)}"
OV_ROOT=$(realpath "$OV_ROOT")
for d in ov_core ov_init ov_msckf config; do
  [ -d "$OV_ROOT/$d" ] || { echo "OV_ROOT=$OV_ROOT lacks $d/" >&2; exit 2; }
done
[ -f "$HARNESS/ov_euroc_harness.cpp" ] || { echo "no harness source in $HARNESS (--harness DIR)" >&2; exit 2; }
[ -x "$BIN" ] || { echo "no ovton binary at $BIN (scripts/build.sh, or --bin)" >&2; exit 2; }
case "$REPEATS" in '' | *[!0-9]* | 0) echo "--repeats needs a positive integer" >&2; exit 2 ;; esac
MD=${MD:-$OUT/peer.md}
mkdir -p "$OUT" "$BUILD"
OUT=$(realpath "$OUT")
JOBS=${JOBS:-2}

# ---- build OpenVINS's library (if missing) and the harness, outside the repository
# (PY_ARGS and the harness's CXX flags: scripts/peer/peer_common.sh.)
if [ ! -f "$OV_ROOT/build/libov_msckf_lib.so" ]; then
  echo "building OpenVINS ov_msckf_lib in $OV_ROOT/build (tens of minutes)" >&2
  cmake -S "$OV_ROOT/ov_msckf" -B "$OV_ROOT/build" -DENABLE_ROS=OFF -DCMAKE_BUILD_TYPE=Release "${PY_ARGS[@]}" >/dev/null
  nice -n 10 make -C "$OV_ROOT/build" -j"$JOBS" ov_msckf_lib >/dev/null
fi
cmake -S "$HARNESS" -B "$BUILD/harness" -DOV_ROOT="$OV_ROOT" -DCMAKE_BUILD_TYPE=Release "${PY_ARGS[@]}" \
  -DCMAKE_CXX_FLAGS="$(ov_cxx_flags "$OV_ROOT")" >/dev/null
nice -n 10 make -C "$BUILD/harness" -j"$JOBS" >/dev/null
HB=$BUILD/harness/ov_euroc_harness
if [ "$EXCHANGE" = 1 ]; then
  cmake -S "$REPO/scripts/peer" -B "$BUILD/exchange" -DOV_ROOT="$OV_ROOT" -DCMAKE_BUILD_TYPE=Release >/dev/null
  nice -n 10 make -C "$BUILD/exchange" -j"$JOBS" ov_track_exchange >/dev/null
fi
XB=$BUILD/exchange/ov_track_exchange
if [ "$STEREO" = 1 ]; then # our harness copy, which adds stereo=1 (its mono is the shared harness's)
  build_peer_harness "$OV_ROOT" "$BUILD/peer" "$JOBS"
fi
HS=$BUILD/peer/ov_euroc_harness
has_cam1() { [ -f "$1/mav0/cam1/data.csv" ] && [ -f "$1/mav0/cam1/sensor.yaml" ]; }

RES=$OUT/results.csv
mkdir -p "$OUT"
HEADER=folder,system,variant,repeat,ape_m,are_deg,td_err_late_ms,final_td_ms,est_ms_frame,cpu_s,feat_per_frame,frames,cit_frames,td_settle_s
if [ "$RESUME" = 0 ] || [ ! -s "$RES" ]; then
  echo "$HEADER" > "$RES"
elif [ "$(head -1 "$RES")" != "$HEADER" ]; then # a results.csv of before the last three columns: they stay empty
  sed -i "1s/.*/$HEADER/" "$RES"
fi
have_row() { # folder system variant repeat: already scored (--resume)
  [ "$RESUME" = 1 ] && grep -qF "$1,$2,$3,$4," "$RES"
}

# score EST (ovton CSV columns) against FOLDER; appends one row to results.csv
score() { # folder system variant repeat est ms_frame cpu_s feat_per_frame
  local f=$1 sys=$2 var=$3 rep=$4 est=$5 msf=$6 cpu=$7 fpf=$8 td=()
  if [ -f "$f/mav0/td_truth/data.csv" ]; then td=(--td-truth "$f/mav0/td_truth/data.csv"); fi
  "$BIN" eval --est "$est" --gt "$f/mav0/state_groundtruth_estimate0/data.csv" --align posyaw "${td[@]}" \
    --json "$est.eval.json" >/dev/null
  python3 - "$est.eval.json" "$est" "$f" "$sys" "$var" "$rep" "$msf" "$cpu" "$fpf" >> "$RES" <<'PY'
import json, sys, csv, os, bisect
j = json.load(open(sys.argv[1])); rows = list(csv.DictReader(open(sys.argv[2])))
late = j.get("td_err_rmse_late_ms")
cit = j.get("cit")
# td_settle_s: seconds from the first estimate to the first one after which |t_d - truth| <= 1 ms holds to the end
# (truth at the image's camera stamp, as `ovton eval` takes it); empty when the last estimate is off or no truth
settle = ""
tdf = os.path.join(sys.argv[3], "mav0/td_truth/data.csv")
if os.path.exists(tdf):
    tt, tv = [], []
    for r in csv.reader(open(tdf)):
        if r and not r[0].startswith("#"):
            tt.append(int(r[0])); tv.append(float(r[1]))
    def truth(t):
        i = bisect.bisect_left(tt, t)
        if i <= 0: return tv[0]
        if i >= len(tt): return tv[-1]
        u = (t - tt[i - 1]) / (tt[i] - tt[i - 1]); return tv[i - 1] + u * (tv[i] - tv[i - 1])
    ts = [int(r["timestamp_ns"]) for r in rows]; td = [float(r["td_s"]) for r in rows]
    ok = [abs(d - truth(t - round(d * 1e9))) <= 1e-3 for t, d in zip(ts, td)]
    if ok and ok[-1]:
        k = len(ok) - 1
        while k > 0 and ok[k - 1]: k -= 1
        settle = f"{(ts[k] - ts[0]) * 1e-9:.2f}"
print(",".join([sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6], f"{j['ape_rmse_m']:.6f}", f"{j['are_rmse_deg']:.4f}",
                "" if late is None else f"{late:.4f}", f"{float(rows[-1]['td_s'])*1e3:.3f}", sys.argv[7], sys.argv[8],
                sys.argv[9], str(len(rows)), "" if cit is None else str(cit), settle]))
PY
}

cpu_of() { awk '{print $1+$2}' "$1"; } # /usr/bin/time -f "%U %S" output

# A view of folder $1 (symlinks) whose IMU noise parameters are $2 times the folder's, or (k = fit) the values
# config/euroc_mav declares; prints its path.
imu_view() {
  local f=$1 k=$2 v
  v=$OUT/$(basename "$f")/view_imu$k
  mkdir -p "$v/mav0/imu0"
  for d in "$f"/mav0/*; do [ "$(basename "$d")" = imu0 ] || ln -sfn "$d" "$v/mav0/$(basename "$d")"; done
  ln -sf "$f/mav0/imu0/data.csv" "$v/mav0/imu0/data.csv"
  if [ "$k" = fit ]; then
    awk 'NR == FNR { if ($1 ~ /^(gyroscope|accelerometer)_(noise_density|random_walk):$/) fit[$1] = $2; next }
         ($1 in fit) { printf "%s %s\n", $1, fit[$1]; next } { print }' \
      "$REPO/config/euroc_mav/estimator_config.yaml" "$f/mav0/imu0/sensor.yaml" > "$v/mav0/imu0/sensor.yaml"
  else
    awk -v k="$k" '/^(gyroscope|accelerometer)_(noise_density|random_walk):/ {printf "%s %.6g\n", $1, $2 * k; next} {print}' \
      "$f/mav0/imu0/sensor.yaml" > "$v/mav0/imu0/sensor.yaml"
  fi
  echo "$v"
}

run_ov() { # folder variant repeat [stereo]
  local f=$1 var=$2 rep=$3 st=${4:-} name pre src=$1 hb=$HB label=$2 extra=()
  if [ "$st" = stereo ]; then label="$var stereo"; hb=$HS; extra=(stereo=1); fi
  if have_row "$f" OpenVINS "$label" "$rep"; then return 0; fi
  name=$(basename "$f")
  pre=$OUT/$name/ov_${var//@/_}${st:+_$st}_r$rep
  mkdir -p "$OUT/$name"
  if [[ $var == *@imu*@pts* ]]; then echo "give @ptsN before @imuK ($var)" >&2; return 0; fi
  if [[ $var == *@imu* ]]; then src=$(imu_view "$f" "${var##*@imu}"); fi
  # shellcheck disable=SC2046
  OV_ROOT=$OV_ROOT nice -n 10 /usr/bin/time -f "%U %S" -o "$pre.time" "$hb" "$src" "$pre" threads=1 $(ov_args "$var") \
    "${extra[@]}" >"$pre.log" 2>&1 || { echo "OpenVINS $label failed on $f (log $pre.log)" >&2; return 0; }
  cut -d, -f1-19 "$pre.csv" > "$pre.est.csv"
  local msf fpf
  msf=$(awk '/feed_measurement_camera/ {print $4}' "$pre"_timing.txt)
  fpf=$(python3 -c "import csv,sys; r=list(csv.DictReader(open(sys.argv[1]))); print(f\"{sum(int(x['n_msckf_used'])+int(x['n_slam']) for x in r)/len(r):.1f}\")" "$pre.csv")
  score "$f" OpenVINS "$label" "$rep" "$pre.est.csv" "$msf" "$(cpu_of "$pre.time")" "$fpf"
}

run_ovton() { # folder mode repeat [stereo]
  local f=$1 mode=$2 rep=$3 st=${4:-} name pre cfg init=() cams=() label=$2
  # a folder with cam1: mono rows say --cameras 0 (ovton's default is every camera the recording has)
  if [ "$st" = stereo ]; then label="$mode stereo"; cams=(--cameras "0,1"); elif has_cam1 "$f"; then cams=(--cameras 0); fi
  if have_row "$f" ovton "$label" "$rep"; then return 0; fi
  name=$(basename "$f")
  pre=$OUT/$name/ovton_${mode//+/_}${st:+_$st}_r$rep
  mkdir -p "$OUT/$name"
  if [ -f "$f/mav0/td_truth/data.csv" ]; then cfg=$CFG_SIM; else cfg=$CFG_REAL; init=(--init groundtruth); fi
  OPENCV_FOR_THREADS_NUM=1 nice -n 10 /usr/bin/time -f "%U %S" -o "$pre.time" "$BIN" run -q --no-prefetch -d "$f" \
    -c "$cfg" -m "$mode" "${init[@]}" "${cams[@]}" -o "$pre.csv" >"$pre.log" 2>&1 ||
    { echo "ovton $label failed on $f (log $pre.log)" >&2; return 0; }
  local msf fpf
  msf=$(sed -n 's/.*tracking \([0-9.]*\), propagation \([0-9.]*\), update \([0-9.]*\);.*/\1 \2 \3/p' "$pre.log" |
    awk '{printf "%.3f", $1+$2+$3}')
  fpf=$(sed -n 's/^mode [^:]*: \([0-9]*\) images.* \([0-9]*\) features used.*/\2 \1/p' "$pre.log" | awk '{printf "%.1f", $1/$2}')
  score "$f" ovton "$label" "$rep" "$pre.csv" "$msf" "$(cpu_of "$pre.time")" "$fpf"
}

IFS=, read -r -a OVV <<< "$OV_VARIANTS"
IFS=, read -r -a OTM <<< "$OVTON_MODES"
for f in "${FOLDERS[@]}"; do
  [ -d "$f/mav0" ] || { echo "$f has no mav0/" >&2; exit 2; }
  echo "== $(basename "$f")" >&2
  for rep in $(seq 1 "$REPEATS"); do
    # Alternate the two systems so that a change in machine load hits both.
    n=$(( ${#OVV[@]} > ${#OTM[@]} ? ${#OVV[@]} : ${#OTM[@]} ))
    for i in $(seq 0 $((n - 1))); do
      if [ "$i" -lt "${#OTM[@]}" ]; then run_ovton "$f" "${OTM[$i]}" "$rep"; fi
      if [ "$i" -lt "${#OVV[@]}" ]; then run_ov "$f" "${OVV[$i]}" "$rep"; fi
      if [ "$STEREO" = 1 ] && has_cam1 "$f"; then
        if [ "$i" -lt "${#OTM[@]}" ]; then run_ovton "$f" "${OTM[$i]}" "$rep" stereo; fi
        if [ "$i" -lt "${#OVV[@]}" ]; then run_ov "$f" "${OVV[$i]}" "$rep" stereo; fi
      fi
    done
  done
  if [ "$STEREO" = 1 ] && ! has_cam1 "$f"; then echo "$(basename "$f") has no mav0/cam1: mono rows only" >&2; fi
  if [ "$EXCHANGE" = 1 ]; then
    name=$(basename "$f")
    X=$OUT/$name/exchange
    mkdir -p "$X"
    if [ -f "$f/mav0/td_truth/data.csv" ]; then cfg=$CFG_SIM; init=(); else cfg=$CFG_REAL; init=(--init groundtruth); fi
    # OpenVINS's matched config for this folder, as the harness writes it
    [ -f "$OUT/$name/ov_matched_r1_config/estimator_config.yaml" ] || run_ov "$f" matched 1
    ovcfg=$OUT/$name/ov_matched_r1_config/estimator_config.yaml
    nice -n 10 "$XB" "$f" "$X/ov_dump" "$ovcfg" dump="$X/ov_tracks.csv" >"$X/ov_dump.log" 2>&1
    nice -n 10 "$BIN" track -d "$f" -c "$cfg" --out "$X/ovton_tracks.csv" >"$X/ovton_track.log"
    for tr in ov ovton; do # a folder that replays the tracks instead of the images
      mkdir -p "$X/on_$tr/mav0/cam0"
      for d in imu0 state_groundtruth_estimate0 td_truth; do
        if [ -e "$f/mav0/$d" ]; then ln -sfn "$f/mav0/$d" "$X/on_$tr/mav0/$d"; fi
      done
      for fl in sensor.yaml data.csv; do ln -sf "$f/mav0/cam0/$fl" "$X/on_$tr/mav0/cam0/$fl"; done
      cp "$X/${tr}_tracks.csv" "$X/on_$tr/mav0/cam0/features.csv"
      OPENCV_FOR_THREADS_NUM=1 nice -n 10 /usr/bin/time -f "%U %S" -o "$X/ovton_on_$tr.time" "$BIN" run -q \
        -d "$X/on_$tr" -c "$cfg" -m sr "${init[@]}" -o "$X/ovton_on_$tr.csv" >"$X/ovton_on_$tr.log" 2>&1
      score "$f" "ovton estimator" "sr on ${tr} tracks" 1 "$X/ovton_on_$tr.csv" "" "$(cpu_of "$X/ovton_on_$tr.time")" \
        "$(sed -n 's/^mode [^:]*: \([0-9]*\) images.* \([0-9]*\) features used.*/\2 \1/p' "$X/ovton_on_$tr.log" | awk '{printf "%.1f", $1/$2}')"
      nice -n 10 /usr/bin/time -f "%U %S" -o "$X/ov_on_$tr.time" "$XB" "$f" "$X/ov_on_$tr" "$ovcfg" \
        feed="$X/${tr}_tracks.csv" >"$X/ov_on_$tr.log" 2>&1
      cut -d, -f1-19 "$X/ov_on_$tr.csv" > "$X/ov_on_$tr.est.csv"
      score "$f" "OpenVINS estimator" "matched on ${tr} tracks" 1 "$X/ov_on_$tr.est.csv" "" "$(cpu_of "$X/ov_on_$tr.time")" \
        "$(python3 -c "import csv,sys; r=list(csv.DictReader(open(sys.argv[1]))); print(f\"{sum(int(x['n_msckf_used']) for x in r)/len(r):.1f}\")" "$X/ov_on_$tr.csv")"
    done
    for tr in ov ovton; do
      "$BIN" track -d "$f" --tracks "$X/${tr}_tracks.csv" --md "$X/${tr}_tracks_score.md" >/dev/null
    done
  fi
done

# ---- the table
python3 - "$RES" "$MD" "$(git -C "$REPO" rev-parse --short HEAD)" "$REPEATS" "$OV_VARIANTS" "$OVTON_MODES" \
  "$(uptime | sed 's/.*load average: //')" "$EXCHANGE" "$OUT" "$STEREO" <<'PY'
import csv, sys, statistics as st, os, collections
res, md, commit, repeats, ovv, otm, load, exchange, out, stereo = sys.argv[1:11]
stereo = stereo == "1"
is_st = lambda var: var.endswith(" stereo")
rows = list(csv.DictReader(open(res)))
def med(xs):
    xs = [float(x) for x in xs if x not in ("", None)]
    return st.median(xs) if xs else None
def fmt(x, d):
    return "–" if x is None else f"{x:.{d}f}"
groups = collections.OrderedDict()
for r in rows:
    groups.setdefault((r["folder"], r["system"], r["variant"]), []).append(r)
# a folder's rows together even when a later run (--resume with more modes or variants) appended some
folder_order = {f: i for i, f in reversed(list(enumerate(r["folder"] for r in rows)))}
groups = collections.OrderedDict(sorted(groups.items(), key=lambda kv: folder_order[kv[0][0]]))
L = []
L.append(f"Commit {commit}; {repeats} run(s) per system and folder, alternating; load average at the end: {load}.")
L.append("")
if not stereo:
    L.append("| folder | system | variant | APE [mm] | ARE [deg] | t_d err RMSE, 2nd half [ms] | final t̂_d [ms] | "
             "ms/frame (no PNG) | CPU [s] | CPU / OpenVINS noslam | features / frame |")
    L.append("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
else: # --stereo: CPU per frame, its ratio to OpenVINS noslam stereo, and t_d's convergence too
    L.append("| folder | system | variant | APE [mm] | ARE [deg] | t_d err RMSE, 2nd half [ms] | final t̂_d [ms] | "
             "ms/frame (no PNG) | CPU [s] | CPU / OpenVINS noslam | features / frame | CPU / frame [ms] | "
             "CPU / OpenVINS noslam stereo | CIT [frames] | t_d within 1 ms from [s] |")
    L.append("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
summary = collections.OrderedDict()
for (f, sysn, var), g in groups.items():
    if sysn not in ("ovton", "OpenVINS"):
        continue
    name = os.path.basename(f)
    ape, are = med(x["ape_m"] for x in g), med(x["are_deg"] for x in g)
    tdl, tdf = med(x["td_err_late_ms"] for x in g), med(x["final_td_ms"] for x in g)
    msf, cpu, fpf = med(x["est_ms_frame"] for x in g), med(x["cpu_s"] for x in g), med(x["feat_per_frame"] for x in g)
    def cpu_ratio(refvar):
        ref = groups.get((f, "OpenVINS", refvar))
        if ref and cpu:
            rc = med(x["cpu_s"] for x in ref)
            return cpu / rc if rc else None
        return None
    ratio = cpu_ratio("noslam")
    line = (f"| {name} | {sysn} | {var} | {fmt(ape*1e3 if ape is not None else None, 1)} | {fmt(are, 3)} | "
            f"{fmt(tdl, 3)} | {fmt(tdf, 2)} | {fmt(msf, 2)} | {fmt(cpu, 1)} | {fmt(ratio, 2)} | {fmt(fpf, 1)} |")
    frames = med(x.get("frames") for x in g)
    cpf = cpu / frames * 1e3 if cpu and frames else None
    if stereo:
        cit = med(x.get("cit_frames") for x in g)
        settle = [x.get("td_settle_s") for x in g]
        settle_s = "–" if not os.path.exists(os.path.join(f, "mav0/td_truth/data.csv")) else (
            "never" if any(v in ("", None) for v in settle) else fmt(med(settle), 2))
        line += (f" {fmt(cpf, 2)} | {fmt(cpu_ratio('noslam stereo'), 2)} | {fmt(cit, 0)} | {settle_s} |")
    L.append(line)
    s = summary.setdefault(name, {"ovton": [], "OpenVINS": [], "ovton st": [], "OpenVINS st": [], "cpf": {}, "cit": {}})
    s[sysn + (" st" if stereo and is_st(var) else "")].append((ape, var))
    s["cpf"][(sysn, var)] = cpf
    s["cit"][(sysn, var)] = (med(x.get("cit_frames") for x in g), settle_s if stereo else None)
L.append("")
if stereo:
    L.append("Monocular rows only:")
    L.append("")
L.append("| folder | best ovton (mode) APE [mm] | best OpenVINS (variant) APE [mm] | ratio ovton / OpenVINS |")
L.append("|---|---|---|---:|")
for name, s in summary.items():
    if not s["ovton"] or not s["OpenVINS"]:
        continue
    a = min(s["ovton"], key=lambda t: t[0]); b = min(s["OpenVINS"], key=lambda t: t[0])
    L.append(f"| {name} | {a[0]*1e3:.1f} ({a[1]}) | {b[0]*1e3:.1f} ({b[1]}) | {a[0]/b[0]:.2f} |")
if stereo:
    # issue 40's bars: ovton stereo APE <= 0.8x ovton mono and <= 0.7x the best OpenVINS stereo variant; CPU per
    # frame <= 0.7x OpenVINS stereo's (here against noslam stereo and against the best-APE stereo variant)
    L.append("")
    L.append("Stereo (each mode's stereo row against the same mode's mono row; OpenVINS's best stereo variant by APE):")
    L.append("")
    L.append("| folder | ovton mode | APE mono → stereo [mm] | stereo / mono | best OpenVINS stereo (variant) APE [mm] | "
             "ovton stereo / OpenVINS stereo | CPU/frame ovton stereo [ms] | / OpenVINS noslam stereo | "
             "/ best OpenVINS stereo | CIT mono → stereo [frames] | t_d within 1 ms from, mono → stereo [s] |")
    L.append("|---|---|---|---:|---|---:|---:|---:|---:|---|---|")
    for name, s in summary.items():
        if not s["ovton st"]:
            continue
        mono = {v: a for a, v in s["ovton"]}
        b = min(s["OpenVINS st"], key=lambda t: t[0]) if s["OpenVINS st"] else None
        for a, v in s["ovton st"]:
            m = v[: -len(" stereo")]
            am = mono.get(m)
            cpf = s["cpf"].get(("ovton", v))
            ref_n = s["cpf"].get(("OpenVINS", "noslam stereo"))
            ref_b = s["cpf"].get(("OpenVINS", b[1])) if b else None
            cm, sm = s["cit"].get(("ovton", m), (None, None)); cs, ss = s["cit"].get(("ovton", v), (None, None))
            L.append(f"| {name} | {m} | {fmt(am*1e3 if am else None, 1)} → {a*1e3:.1f} | {fmt(a/am if am else None, 2)} | "
                     + (f"{b[0]*1e3:.1f} ({b[1][: -len(' stereo')]}) | {a/b[0]:.2f} | " if b else "– | – | ")
                     + f"{fmt(cpf, 2)} | {fmt(cpf/ref_n if cpf and ref_n else None, 2)} | "
                     f"{fmt(cpf/ref_b if cpf and ref_b else None, 2)} | {fmt(cm, 0)} → {fmt(cs, 0)} | {sm} → {ss} |")
if exchange == "1":
    L.append("")
    L.append("Front ends swapped (`--exchange`): each estimator on its own and on the other's tracks (ovton sr with its "
             "config; OpenVINS with the matched variant's config), APE [mm] / features per frame:")
    L.append("")
    L.append("| folder | ovton estimator, ovton tracks | ovton estimator, OpenVINS tracks | OpenVINS estimator, OpenVINS tracks | OpenVINS estimator, ovton tracks |")
    L.append("|---|---:|---:|---:|---:|")
    names = collections.OrderedDict((os.path.basename(r["folder"]), r["folder"]) for r in rows)
    for name, f in names.items():
        def get(sysn, var):
            g = groups.get((f, sysn, var))
            if not g: return "–"
            return f"{float(g[0]['ape_m'])*1e3:.1f} / {g[0]['feat_per_frame']}"
        L.append(f"| {name} | {get('ovton estimator', 'sr on ovton tracks')} | {get('ovton estimator', 'sr on ov tracks')} | "
                 f"{get('OpenVINS estimator', 'matched on ov tracks')} | {get('OpenVINS estimator', 'matched on ovton tracks')} |")
open(md, "w").write("\n".join(L) + "\n")
print("\n".join(L))
PY
echo "table: $MD; runs: $OUT" >&2
