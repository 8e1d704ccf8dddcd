# Sourced by the experiment scripts: fields of `ovton run`'s summary and the sim(3) scale error of `ovton eval`.
# Usage: LINE=$(ovton run ... -q); nees_ori "$LINE"; nees_pos "$LINE"; ape_m "$LINE"; final_td_ms "$LINE";
#        scale_error_pct BIN EST_CSV GT_CSV
nees_ori() { echo "$1" | sed -n 's/^NEES orientation \([0-9.]*\), position \([0-9.]*\).*/\1/p'; }
nees_pos() { echo "$1" | sed -n 's/^NEES orientation \([0-9.]*\), position \([0-9.]*\).*/\2/p'; }
ape_m() { echo "$1" | sed -n 's/^APE \([0-9.]*\) m.*/\1/p'; }
final_td_ms() { echo "$1" | sed -n 's/^final t_d \([-0-9.]*\) ms.*/\1/p'; }
# How much too large the estimate is after a sim(3) fit: a monocular VIO's scale error, in %.
scale_error_pct() {
  "$1" eval --est "$2" --gt "$3" --align sim3 | sed -n 's/.*scale [0-9.]*: estimate \([-0-9.]*\) % too large.*/\1/p'
}
