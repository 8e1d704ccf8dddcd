#!/usr/bin/env bash
# Issue #13: why is the real V1_01 IMU log harder for `sr` than the synthetic error model? Transplant its residual.
# On a span of V1_01 (4.62 s from SPAN start, EuRoC's own V1_01 ground truth, --realism euroc, +10 ms), per scene
# (seed) one fully synthetic folder is rendered; every other folder is a copy of it (same images, ground truth
# poses, stamps, imu0/sensor.yaml with the fitted noise) whose imu0/data.csv is ideal(span spline) + a residual:
#   syn   the synthetic error model as written by `ovton simulate` (no copy)
#   semi  the real log as `ovton simulate --imu-from` writes it (its imu0/data.csv and ground truth copied in)
#   Se    the span's own real residual r = real - ideal, EuRoC's bias columns (= semi, a check of the construction)
#   S     the span's own residual, constant bias columns (the flight mean of r: the model's convention)
#   T     the residual of two other spans of the same log (start + 10..120 s, wrapped into the flight, two per
#         scene), constant bias columns
#   P     phase-randomised flight residual (same phases on all 6 channels), constant bias columns
#   Pi    phase-randomised, independent phases per channel
#   Sf Tf Pf Pif  as S T P Pi with u taken out of the residual first: u is the motion the folders' spline (EuRoC's
#         20 Hz ground truth, knots 0.1 s) misses and the real IMU saw - the ideal IMU along the 200 Hz
#         euroc_groundtruth/V1_01_easy.txt (knots 0.03 s) minus that along the folders' spline, above 1.5 Hz
#   Sef   Se with u taken out (the real log as a semi-real folder would carry it had its images followed the motion)
#   U     the synthetic folder's own IMU (error model) + u of this span; its own ground truth (bias columns) kept
#   Ug Ua Ulo Uhi  U with only u's gyro / accelerometer part, only u below / above 10 Hz
# and `sr` (config/sim/estimator_config.yaml, ground-truth initialisation) runs on each; APE/ARE from `ovton eval
# --align posyaw` (unrounded). The residual is taken against the ideal IMU along the simulator's spline of the very
# span (`--no-imu-noise --imu-errors none --no-images`, same start/duration: same spline and stamps as the folders).
#
# Usage (from anywhere; runs in the repo root):
#   [SPANS="s1 s2 ..."] [OVTON_BIN=build/ovton] [PYTHON=python3] scripts/experiments/imu_surrogate.sh [OUT] [SEEDS] [VARIANTS]
#   OUT       default results/imu_surrogate (a relative OUT is taken from the repo root)
#   SPANS     span starts [s after the ground truth's first pose]; default 11.9 (the real cut's span: its first
#             image is 12.0 s in); SPANS=ten is the ten spans of imu_realism.sh (15 27 39 ... 123 s)
#   SEEDS     N: scenes 1..N on every span (default 10); start: one scene per span whose seed is the span's start
#             (integer starts only), as imu_realism.sh does
#   VARIANTS  default: all of the above; " " only rewrites the summary
#   OVTON_BIN a copy of the binary (to go on building while it runs); PYTHON needs numpy
# e.g. (issue 13)   scripts/experiments/imu_surrogate.sh results/imu_surrogate 30
#                   SPANS=ten scripts/experiments/imu_surrogate.sh results/imu_surrogate_spans start
# Writes OUT/runs.txt (variant span seed APE_m ARE_deg), OUT/resid_report.md (band levels of r and of r - u,
# coherences, lines, kurtosis), OUT/summary.md (mean over runs; "/ syn" = ratio of means on the same scenes; "paired"
# = geometric mean over scenes of variant / syn; with several spans also a table per span). Rendered folders in
# OUT/work are reused and runs.txt is appended to: a fresh table needs a fresh OUT (or spans/seeds/variants not run
# before). Needs ../shared/data. ~1-2 s per run and ~5 s per rendered scene on 2 busy cores.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
[ -f "$HERE/../../config/sim/estimator_config.yaml" ] && cd "$HERE/../.." # else: a copy run from the repo root
OUT=${1:-results/imu_surrogate}
SEEDS=${2:-10}
VARIANTS=${3:-"syn semi Se S T P Pi Sf Sef Tf Pf Pif U Ug Ua Ulo Uhi"}
SPANS=${SPANS:-11.9}
[ "$SPANS" = ten ] && SPANS="15 27 39 51 63 75 87 99 111 123"
PY=${PYTHON:-python3}
surr() { nice -n 10 "$PY" "$HERE/imu_surrogate.py" "$@"; }
DATA=../shared/data
CUT=$DATA/euroc_v1_01_moving
GT=$CUT/mav0/state_groundtruth_estimate0/data.csv
REAL=$CUT/mav0/imu0/data.csv
TXT=$DATA/euroc_groundtruth/V1_01_easy.txt
BIN=${OVTON_BIN:-build/ovton}
[ -x "$BIN" ] || scripts/build.sh
DUR=4.62
OFFSETS=(10 20 30 40 50 60 70 80 90 100 110 120) # T: source span = start + offset, wrapped into [4, 143 - DUR] s
NICE="nice -n 10"
mkdir -p "$OUT/ideal" "$OUT/work"
: >> "$OUT/runs.txt"

ideal() { # START -> folder with the ideal IMU along the spline of that span
  local d="$OUT/ideal/$1"
  [ -d "$d/mav0" ] || $NICE "$BIN" simulate --gt "$GT" --start-s "$1" --duration-s "$DUR" --no-imu-noise \
    --imu-errors none --no-images --out "$d" -q > /dev/null
  echo "$d"
}
W=$(cd "$OUT" && pwd)/ideal/whole
[ -d "$W/mav0" ] || $NICE "$BIN" simulate --gt "$GT" --start-s 0 --duration-s 144.6 --no-imu-noise --imu-errors none \
  --no-images --out "$W" -q > /dev/null
[ -f "$OUT/resid.npz" ] || surr prep --real "$REAL" --ideal-whole "$W" --out "$OUT/resid.npz" > "$OUT/resid_report.md"
F=$(cd "$OUT" && pwd)/ideal/fine_txt
if [ ! -d "$F/mav0" ]; then
  $NICE "$BIN" simulate --gt "$TXT" --start-s 0.1 --duration-s 143.4 --knot-dt-s 0.03 --no-imu-noise --imu-errors none \
    --no-images --out "$F" -q > /dev/null
  surr prep-unres --npz "$OUT/resid.npz" --ideal-whole "$W" --ideal-fine "$F" >> "$OUT/resid_report.md"
fi

score() { # KIND SEED FOLDER -> appends "KIND START SEED APE_m ARE_deg" to runs.txt
  local ape
  $NICE "$BIN" run -d "$3" -c config/sim/estimator_config.yaml -o "$3.csv" -q > /dev/null || {
    echo "$1 $START $2 fail fail" >> "$OUT/runs.txt"
    return
  }
  $NICE "$BIN" eval --est "$3.csv" --gt "$3/mav0/state_groundtruth_estimate0/data.csv" --align posyaw --json "$3.json" > /dev/null
  ape=$("$PY" -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['ape_rmse_m'], j['are_rmse_deg'])" "$3.json")
  echo "$1 $START $2 $ape" >> "$OUT/runs.txt"
}

[ -n "${VARIANTS// /}" ] || SPANS="" # VARIANTS " ": summary only
for START in $SPANS; do
  IS=$(ideal "$START")
  if [ "$SEEDS" = start ]; then
    [[ $START =~ ^[0-9]+$ ]] || { echo "SEEDS=start needs integer span starts (got $START)" >&2; exit 2; }
    seeds=$START
  else
    seeds=$(seq 1 "$SEEDS")
  fi
  for s in $seeds; do
    tag=${START}_$s
    syn="$OUT/work/syn_$tag"
    [ -d "$syn/mav0" ] || $NICE "$BIN" simulate --realism euroc --gt "$GT" --start-s "$START" --duration-s "$DUR" \
      --seed "$s" --out "$syn" -q > /dev/null
    for v in $VARIANTS; do
      d="$OUT/work/${v}_$tag"
      fine=""
      case $v in Sf | Sef | Tf | Pf | Pif) fine=--fine ;; esac
      case $v in
        syn) score syn "$s" "$syn" ;;
        semi)
          # The real log as --imu-from writes it; its images are those of syn (checked: byte-identical).
          sr="$OUT/work/semiimu_$tag"
          [ -d "$sr/mav0" ] || $NICE "$BIN" simulate --realism euroc --gt "$GT" --start-s "$START" --duration-s "$DUR" \
            --seed "$s" --imu-from "$CUT" --no-images --out "$sr" -q > /dev/null
          rm -rf "$d"
          cp -al "$syn" "$d"
          for f in imu0/data.csv imu0/sensor.yaml state_groundtruth_estimate0/data.csv; do
            rm "$d/mav0/$f"
            cp "$sr/mav0/$f" "$d/mav0/$f"
          done
          score semi "$s" "$d" ;;
        Se | Sef)
          surr write --syn "$syn" --out "$d" --ideal "$IS" --variant S --src-ideal "$IS" --real "$REAL" \
            --npz "$OUT/resid.npz" --bias euroc --euroc-gt "$GT" $fine > /dev/null
          score "$v" "$s" "$d" ;;
        S | Sf)
          surr write --syn "$syn" --out "$d" --ideal "$IS" --variant S --src-ideal "$IS" --real "$REAL" \
            --npz "$OUT/resid.npz" $fine > /dev/null
          score "$v" "$s" "$d" ;;
        T | Tf)
          for k in 0 1; do
            off=${OFFSETS[$(((2 * (s - 1) + k) % ${#OFFSETS[@]}))]}
            src=$(ideal "$("$PY" -c "print(round(4 + ($START - 4 + $off) % (143 - 4 - $DUR), 3))")")
            d="$OUT/work/${v}${off}_$tag"
            surr write --syn "$syn" --out "$d" --ideal "$IS" --variant T --src-ideal "$src" --real "$REAL" \
              --npz "$OUT/resid.npz" $fine > /dev/null
            score "$v" "$s" "$d"
            rm -rf "$d"
          done ;;
        P | Pi | Pf | Pif)
          surr write --syn "$syn" --out "$d" --ideal "$IS" --variant "${v%f}" --npz "$OUT/resid.npz" --seed "$s" \
            $fine > /dev/null
          score "$v" "$s" "$d" ;;
        U | Ug | Ua | Ulo | Uhi)
          part=$(case $v in U) echo all ;; Ug) echo gyro ;; Ua) echo accel ;; Ulo) echo lo ;; Uhi) echo hi ;; esac)
          surr write --syn "$syn" --out "$d" --ideal "$IS" --variant U --npz "$OUT/resid.npz" --bias syn \
            --u-part "$part" > /dev/null
          score "$v" "$s" "$d" ;;
        *)
          echo "unknown variant $v" >&2
          exit 2 ;;
      esac
      [ "$v" = syn ] || rm -rf "$d"
    done
  done
done

"$PY" - "$OUT" "$(git rev-parse --short HEAD 2> /dev/null || echo '?')" "$BIN" "$DUR" <<'PY' > "$OUT/summary.md"
import sys, collections, math
out, commit, binary, dur = sys.argv[1:5]
runs = collections.defaultdict(lambda: collections.defaultdict(list))  # variant -> (span, seed) -> [(APE mm, ARE)]
for line in open(f"{out}/runs.txt"):
    k, span, s, ape, are = line.split()
    if ape != "fail":
        runs[k][(float(span), int(s))].append((1000 * float(ape), float(are)))
names = {"syn": "synthetic error model", "semi": "real log (--imu-from)", "Se": "Se: own residual, EuRoC bias cols (= semi)",
         "S": "S: own residual", "T": "T: other spans' residual", "P": "P: phase-randomised, shared phases",
         "Pi": "Pi: phase-randomised, independent phases", "Sf": "Sf: S without u", "Sef": "Sef: Se without u",
         "Tf": "Tf: T without u", "Pf": "Pf: P without u", "Pif": "Pif: Pi without u", "U": "U: synthetic + u",
         "Ug": "Ug: synthetic + u's gyro part", "Ua": "Ua: synthetic + u's accel part",
         "Ulo": "Ulo: synthetic + u below 10 Hz", "Uhi": "Uhi: synthetic + u above 10 Hz"}
order = [k for k in names if k in runs] + sorted(set(runs) - set(names))
mean = lambda x: sum(x) / len(x)
per = {k: {key: mean([a for a, _ in v]) for key, v in runs[k].items()} for k in runs}  # mean APE per scene
syn = per.get("syn", {})
semi = per.get("semi", {})
spans = sorted({sp for k in runs for sp, _ in runs[k]})
scenes = sorted({key for k in runs for key in runs[k]})
seeds = collections.defaultdict(list)
for sp, s in scenes:
    seeds[sp].append(s)
fmt = lambda sp: f"{sp:g}"
desc = "; ".join(f"{fmt(sp)} s (seeds {', '.join(map(str, v)) if len(v) < 4 else f'{v[0]}–{v[-1]}'})" for sp, v in seeds.items())
print(f"# Real IMU residual transplanted into synthetic folders (issue 13)\n\nrepo {commit}, binary {binary}; "
      f"spans of {dur} s from {desc}; sr, config/sim. APE/ARE: ovton eval --align posyaw (RMSE).\n")


def ratio(p, ref):  # ratio of means over the scenes both have
    ks = [key for key in p if key in ref]
    return mean([p[key] for key in ks]) / mean([ref[key] for key in ks]) if ks else float("nan")


def paired(p, ref):  # geometric mean of p / ref over scenes, and its multiplicative standard error
    lr = [math.log(p[key] / ref[key]) for key in p if key in ref]
    if len(lr) < 2:
        return "–"
    m = mean(lr)
    se = math.sqrt(sum((x - m) ** 2 for x in lr) / (len(lr) - 1) / len(lr))
    return f"{math.exp(m):.2f} (×/÷ {math.exp(se):.2f})"


print(f"Pooled over {len(spans)} span(s), {len(scenes)} scene(s):\n")
print("| variant | runs | APE [mm] mean (min–max) | ARE [deg] | / syn | / semi | paired / syn (×/÷ s.e.) |")
print("|---|---|---|---|---|---|---|")
for k in order:
    ape = [a for v in runs[k].values() for a, _ in v]
    are = [r for v in runs[k].values() for _, r in v]
    print(f"| {names.get(k, k)} | {len(ape)} | {mean(ape):.1f} ({min(ape):.1f}–{max(ape):.1f}) | {mean(are):.2f} | "
          f"{ratio(per[k], syn):.2f} | {ratio(per[k], semi):.2f} | {paired(per[k], syn)} |")
if len(spans) > 1:
    print("\nPer span: APE [mm], mean over the span's scenes (T-type variants: over both source spans)\n")
    print("| span [s] | " + " | ".join(order) + " | semi / syn | Sef / syn |")
    print("|---|" + "---|" * (len(order) + 2))
    for sp in spans:
        sub = lambda k: {key: v for key, v in per[k].items() if key[0] == sp}
        cells = [f"{mean(list(sub(k).values())):.1f}" if sub(k) else "–" for k in order]
        rr = [f"{ratio(sub(k), sub('syn')):.2f}" if k in per and sub(k) and "syn" in per else "–" for k in ("semi", "Sef")]
        print(f"| {fmt(sp)} | " + " | ".join(cells) + " | " + " | ".join(rr) + " |")
if "Sef" in per and syn:
    r = ratio(per["Sef"], syn)
    print(f"\nSemi-real with u removed (Sef) / synthetic: ratio of means {r:.2f}, paired {paired(per['Sef'], syn)} "
          f"-> {'within' if r <= 1.5 else 'outside'} 1.5×.")
PY
cat "$OUT/summary.md"
