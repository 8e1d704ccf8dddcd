#!/usr/bin/env bash
# Issue #13's image table: `ovton trackstats` on the real moving V1_01 cut and on renderings of the same span
# (image stamps 1403715285.26-1403715289.71 s) with --realism clean and euroc (SEEDS scenes each), and on euroc and
# clean renderings of equally long windows of V1_03_difficult and V2_03_difficult. Writes OUT/summary.md.
# Usage: scripts/experiments/realism_table.sh [OUT] [SEEDS]     (needs ../shared/data; ~15 min on one busy core)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-results/realism_table}
SEEDS=${2:-5}
DATA=../shared/data
GT=$DATA/euroc_groundtruth
BIN=build/ovton
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"
REAL=$DATA/euroc_v1_01_moving
# The span's first image is 1403715285262142976 ns; the V1_01 .txt ground truth starts at 1403715274.30214 s and
# the simulator's first image comes first_image_s = 0.1 s after the start: --start-s 10.860002976. 4.62 s hold
# the 90 images (plus half the longest exposure after the last).
SPAN="--gt $GT/V1_01_easy.txt --start-s 10.860002976 --duration-s 4.62 --td0-ms 0"
WIN=4.62

"$BIN" trackstats -d "$REAL" -o "$OUT/real" >/dev/null
for r in clean euroc; do
  for s in $(seq 1 "$SEEDS"); do
    D="$OUT/v101_${r}_$s"
    [ -d "$D/mav0" ] || nice -n 10 "$BIN" simulate --realism "$r" $SPAN --seed "$s" --out "$D" -q >/dev/null
    "$BIN" trackstats -d "$D" -o "$D/trackstats" >/dev/null
  done
done
# Faster sequences: three windows of the same length in flight, one scene (seed) per window.
for SEQ in V1_03_difficult V2_03_difficult; do
  for st in 20 40 60; do
    for r in clean euroc; do
      D="$OUT/${SEQ}_${st}_$r"
      [ -d "$D/mav0" ] || nice -n 10 "$BIN" simulate --realism "$r" --gt "$GT/$SEQ.txt" --start-s "$st" \
        --duration-s "$WIN" --td0-ms 0 --seed "$st" --out "$D" -q >/dev/null
      "$BIN" trackstats -d "$D" -o "$D/trackstats" >/dev/null
    done
  done
done

python3 - "$OUT" "$SEEDS" "$(git rev-parse --short HEAD)" > "$OUT/summary.md" <<'PY'
import glob, math, os, sys
out, seeds, commit = sys.argv[1], int(sys.argv[2]), sys.argv[3]

def read(path):
    d = {}
    for line in open(path):
        if ':' in line and not line.startswith('tracker'):
            k, v = line.split(':', 1)
            try:
                d[k.strip()] = float(v.split('#')[0])
            except ValueError:
                pass
    return d

def rate(folder):
    """Median and 95th percentile of the gyro's rate norm over the folder's IMU log [rad/s]."""
    w = []
    for line in open(os.path.join(folder, 'mav0/imu0/data.csv')):
        if line.startswith('#'):
            continue
        f = line.split(',')
        w.append(math.sqrt(sum(float(x) ** 2 for x in f[1:4])))
    w.sort()
    return w[len(w) // 2], w[int(0.95 * (len(w) - 1))]

keys = [('track_length_median', 'median track [frames]', 1, 1), ('new_feature_share_mean', 'new features [%/frame]', 100, 2),
        ('low_gradient_share', 'plain pixels [%]', 100, 1), ('gradient_median', 'Sobel median', 1, 1),
        ('noise_sigma', 'noise σ [grey]', 1, 2), ('fb_reject_share', 'FB rejects [%]', 100, 2),
        ('tracked_per_frame_median', 'tracked/frame', 1, 0)]

def row(name, files, folders):
    vals = [read(f) for f in files]
    cells = []
    for k, _, scale, dec in keys:
        v = [x[k] * scale for x in vals]
        m = sum(v) / len(v)
        cells.append(f"{m:.{dec}f}" if len(v) == 1 else f"{m:.{dec}f} ({min(v):.{dec}f}–{max(v):.{dec}f})")
    r = [rate(f) for f in folders]
    cells.append(f"{sum(x[0] for x in r) / len(r):.2f} / {sum(x[1] for x in r) / len(r):.2f}")
    return f"| {name} | {len(files)} | " + " | ".join(cells) + " |", [read(f) for f in files]

real = os.path.join(out, 'real/summary.yaml')
print("# Rendered vs real images: track statistics (issue 13)\n")
print(f"Made by `scripts/experiments/realism_table.sh {out} {seeds}` (commit {commit}), `ovton trackstats` defaults: "
      "Shi-Tomasi + pyramidal LK 21×21, 3 pyramid images, forward-backward < 0.5 px, 200 points, 15 px mask. "
      "Several scenes: mean (min–max).\n")
print("| images | runs | " + " | ".join(k[1] for k in keys) + " | gyro rate median / p95 [rad/s] |")
print("|---|---|" + "---|" * (len(keys) + 1))
line, rv = row("real V1_01 moving cut", [real], ['../shared/data/euroc_v1_01_moving'])
print(line)
means = {}
for r in ('clean', 'euroc'):
    files = sorted(glob.glob(os.path.join(out, f'v101_{r}_*/trackstats/summary.yaml')))
    line, v = row(f"{r}, same V1_01 span", files, [os.path.dirname(os.path.dirname(f)) for f in files])
    means[r] = {k: sum(x[k] for x in v) / len(v) for k, *_ in keys}
    print(line)
for seq in ('V1_03_difficult', 'V2_03_difficult'):
    for r in ('clean', 'euroc'):
        files = sorted(glob.glob(os.path.join(out, f'{seq}_*_{r}/trackstats/summary.yaml')))
        line, v = row(f"{r}, {seq} (3 windows)", files, [os.path.dirname(os.path.dirname(f)) for f in files])
        means[f'{seq}_{r}'] = {k: sum(x[k] for x in v) / len(v) for k, *_ in keys}
        print(line)
rr = rv[0]
print("\nAcceptance (euroc on the V1_01 span against the real cut, means over scenes):\n")
for r in ('clean', 'euroc'):
    m = means[r]
    t = m['track_length_median'] / rr['track_length_median'] - 1
    n = m['new_feature_share_mean'] / rr['new_feature_share_mean'] - 1
    g = 100 * (m['low_gradient_share'] - rr['low_gradient_share'])
    ok = lambda c: 'within' if c else 'OUTSIDE'
    print(f"- {r}: median track {100 * t:+.0f} % ({ok(abs(t) <= 0.3)} ±30 %), new-feature share {100 * n:+.0f} % "
          f"({ok(abs(n) <= 0.3)} ±30 %), plain pixels {g:+.1f} points ({ok(abs(g) <= 10)} ±10).")
for seq in ('V1_03_difficult', 'V2_03_difficult'):
    m = means[f'{seq}_euroc']
    print(f"- euroc along {seq}: median track {m['track_length_median']:.1f} vs {means['euroc']['track_length_median']:.1f} "
          f"on V1_01, new features {100 * m['new_feature_share_mean']:.2f} vs "
          f"{100 * means['euroc']['new_feature_share_mean']:.2f} %/frame.")
PY
cat "$OUT/summary.md"
