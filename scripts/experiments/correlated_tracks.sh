#!/usr/bin/env bash
# Is the AR(1) model of correlated track errors (update.track_correlation, slam.track_correlation) right for KLT?
# On one rendered folder: the KLT tracks as tracked, and the same tracks rewritten as their points' exact projections
# plus AR(1) errors with a given sigma and correlation (`ovton track --rewrite ar1:S:RHO`); `sr` on both (features.csv
# in a copy of the folder's cam0/), with the shipped independent weights and with the correlation modelled.
# Usage: scripts/experiments/correlated_tracks.sh OUT FOLDER [SIGMA_PX RHO]   (default 0.36 0.89: KLT's on a rendered
# V1_02 flight, `ovton track --score`). OVTON_BIN, CONFIG (default config/sim/estimator_config.yaml). Writes
# OUT/correlated_tracks.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: correlated_tracks.sh OUT FOLDER [SIGMA_PX RHO]}
SRC=$(realpath "${2:?usage: correlated_tracks.sh OUT FOLDER [SIGMA_PX RHO]}")
SIG=${3:-0.36}
RHO=${4:-0.89}
BIN=${OVTON_BIN:-build/ovton}
CONFIG=${CONFIG:-config/sim/estimator_config.yaml}
[ -x "$BIN" ] || scripts/build.sh
mkdir -p "$OUT"

# A copy of the folder whose cam0/ holds features.csv (everything else linked).
copy_with_tracks() {
  local D=$1
  rm -rf "$D"
  mkdir -p "$D/mav0/cam0"
  for x in "$SRC"/mav0/*; do [ "$(basename "$x")" = cam0 ] || ln -s "$x" "$D/mav0/"; done
  for x in "$SRC"/mav0/cam0/*; do ln -s "$x" "$D/mav0/cam0/"; done
  for x in "$SRC"/*; do [ "$(basename "$x")" = mav0 ] || ln -s "$x" "$D/"; done
}
copy_with_tracks "$OUT/klt"
copy_with_tracks "$OUT/ar1"
"$BIN" track -d "$SRC" -c "$CONFIG" -o "$OUT/klt/mav0/cam0/features.csv" >/dev/null
"$BIN" track -d "$SRC" -c "$CONFIG" --rewrite "ar1:$SIG:$RHO" -o "$OUT/ar1/mav0/cam0/features.csv" >/dev/null
"$BIN" track -d "$OUT/klt" --tracks "$OUT/klt/mav0/cam0/features.csv" --score --md "$OUT/klt_score.md" >/dev/null

# name | update.track_correlation update.sigma_px update.chi2_multiplier | the same for slam
VARIANTS=(
  "shipped (independent)|-"
  "independent at the AR(1) sigma|0 $SIG 1 0 $SIG 1"
  "AR(1) modelled, shipped sigmas|0.9 - - 0.9 - -"
  "AR(1) modelled at its sigma and rho|$RHO $SIG 1 $RHO $SIG 1"
)
{
  echo "# Correlated track errors: KLT's tracks against AR(1) tracks"
  echo
  echo "Made by \`scripts/experiments/correlated_tracks.sh $OUT $2 $SIG $RHO\` at commit $(git rev-parse --short HEAD)" \
    "(config $CONFIG, mode sr, ground-truth initialisation). AR(1) tracks: the KLT tracks' points projected exactly, plus AR(1) errors of sigma" \
    "$SIG px and correlation $RHO between consecutive images."
  echo
  echo "| tracks | filter's model | APE [m] | ARE [deg] | NEES ori / pos |"
  echo "|---|---|---:|---:|---|"
} >"$OUT/correlated_tracks.md"
for T in klt ar1; do
  for V in "${VARIANTS[@]}"; do
    NAME=${V%%|*}
    read -r -a P <<<"${V#*|}"
    CFG="$OUT/${T}_$(echo "$NAME" | tr -c 'A-Za-z0-9\n' '_').yaml"
    python3 - "$CONFIG" "$CFG" "${P[@]}" <<'EOF'
import sys, yaml
cfg = yaml.safe_load(open(sys.argv[1]))
p = sys.argv[3:]
if p and p[0] != "-":
    for sec, vals in (("update", p[0:3]), ("slam", p[3:6])):
        for key, v in zip(("track_correlation", "sigma_px", "chi2_multiplier"), vals):
            if v != "-":
                cfg.setdefault(sec, {})[key] = float(v)
yaml.safe_dump(cfg, open(sys.argv[2], "w"))
EOF
    LOG="${CFG%.yaml}.log"
    "$BIN" run -q -d "$OUT/$T" -c "$CFG" -m sr --init groundtruth -o "${CFG%.yaml}.csv" >"$LOG" 2>&1
    python3 - "$LOG" "$T" "$NAME" >>"$OUT/correlated_tracks.md" <<'EOF'
import re, sys
t = open(sys.argv[1]).read()
ape = re.search(r"APE ([0-9.]+) m, ARE ([0-9.]+) deg", t)
nees = re.search(r"NEES orientation ([0-9.]+), position ([0-9.]+)", t)
if not ape:
    sys.exit(f"correlated_tracks.sh: no APE in {sys.argv[1]}")
nees_txt = f"{nees.group(1)} / {nees.group(2)}" if nees else "–"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {ape.group(1)} | {ape.group(2)} | {nees_txt} |")
EOF
  done
done
{
  echo
  echo "KLT's own tracks, scored against the truth (\`ovton track --score\`):"
  echo
  cat "$OUT/klt_score.md"
} >>"$OUT/correlated_tracks.md"
cat "$OUT/correlated_tracks.md"
