#!/usr/bin/env bash
# scripts/quickstart.sh on a fresh Debian 12 system, timed from the clone to its printed table (docs/quickstart.md,
# "How long it takes"). Where no container or VM can be started, a chroot is the nearest thing to a fresh machine:
# debootstrap's minbase (what the debian:12 image holds: apt and the required packages, no compiler, no ccache cache)
# with the image's apt sources (bookworm, bookworm-updates, bookworm-security), the clone copied in, and the quickstart
# run inside it as a user would run it. The kernel, the CPUs and the network are this machine's.
# Needs root and debootstrap (apt-get install debootstrap). Usage:
#   scripts/experiments/fresh_quickstart.sh WORKDIR [COMMIT]      (COMMIT: default HEAD of this clone)
# WORKDIR/base.tar keeps the bootstrapped system between runs (delete it to bootstrap again); every run unpacks it
# into WORKDIR/root afresh. The quickstart's own log: WORKDIR/quickstart.log; the times: WORKDIR/times.txt.
# Environment: APT_DL_LIMIT_KBPS=N caps apt's download rate inside the system (Acquire::http::Dl-Limit, kB/s; 12500 is
# a 100 Mbit/s link), since this sandbox's mirror answers at >100 MB/s; FRESH_CMD replaces the command run inside
# (e.g. 'time scripts/install_deps.sh --minimal' to time the install step alone).
set -euo pipefail
WORK=${1:?usage: fresh_quickstart.sh WORKDIR [COMMIT]}
COMMIT=${2:-HEAD}
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
MIRROR=${MIRROR:-http://deb.debian.org/debian}
[ "$(id -u)" -eq 0 ] || { echo "fresh_quickstart: needs root (chroot, mounts)" >&2; exit 2; }
command -v debootstrap >/dev/null || { echo "fresh_quickstart: apt-get install debootstrap" >&2; exit 2; }
mkdir -p "$WORK"
WORK="$(cd "$WORK" && pwd)"
ROOT="$WORK/root"
if [ ! -f "$WORK/base.tar" ]; then
  rm -rf "$ROOT"
  echo "== debootstrap --variant=minbase bookworm (once; kept in $WORK/base.tar) =="
  debootstrap --variant=minbase bookworm "$ROOT" "$MIRROR" >"$WORK/debootstrap.log"
  cat >"$ROOT/etc/apt/sources.list" <<EOF
deb $MIRROR bookworm main
deb $MIRROR bookworm-updates main
deb http://deb.debian.org/debian-security bookworm-security main
EOF
  # As in the debian:12 image: no package lists until the user's `apt-get update`.
  rm -rf "$ROOT"/var/lib/apt/lists/* "$ROOT"/var/cache/apt/archives/*.deb
  tar -C "$ROOT" -cf "$WORK/base.tar" .
fi
cleanup() {
  for m in dev/pts dev proc sys; do
    mountpoint -q "$ROOT/$m" && umount -l "$ROOT/$m"
  done
  return 0
}
trap cleanup EXIT
cleanup
rm -rf "$ROOT"
mkdir -p "$ROOT"
tar -C "$ROOT" -xf "$WORK/base.tar"
cp /etc/resolv.conf "$ROOT/etc/resolv.conf"
if [ -n "${APT_DL_LIMIT_KBPS:-}" ]; then
  echo "Acquire::http::Dl-Limit \"$APT_DL_LIMIT_KBPS\";" >"$ROOT/etc/apt/apt.conf.d/99dl-limit"
fi
FRESH_CMD=${FRESH_CMD:-scripts/quickstart.sh}
mount -t proc proc "$ROOT/proc"
mount --rbind /sys "$ROOT/sys"
mount --rbind /dev "$ROOT/dev"
# The clone a user would have: the commit's tree only (no build folder, no out/, no ccache).
mkdir -p "$ROOT/root/ov_msckf_ton"
git -C "$SRC" archive "$COMMIT" | tar -C "$ROOT/root/ov_msckf_ton" -x
echo "== $FRESH_CMD in the fresh system: commit $(git -C "$SRC" rev-parse --short "$COMMIT"), $(nproc) cores," \
  "load $(cut -d' ' -f1-3 /proc/loadavg), apt download limit ${APT_DL_LIMIT_KBPS:-none} kB/s =="
START=$(date +%s)
chroot "$ROOT" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  LANG=C.UTF-8 DEBIAN_FRONTEND=noninteractive /bin/bash -c "cd /root/ov_msckf_ton && $FRESH_CMD" \
  2>&1 | tee "$WORK/quickstart.log"
END=$(date +%s)
{
  echo "commit $(git -C "$SRC" rev-parse --short "$COMMIT")"
  grep '^quickstart: install' "$WORK/quickstart.log" || true
  echo "wall from start to the printed table: $((END - START)) s; load at the end $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$WORK/times.txt"
