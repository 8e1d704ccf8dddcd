#!/usr/bin/env bash
# What apt would fetch and install on a fresh Debian 12 for scripts/install_deps.sh --minimal (quickstart) against the
# full set (tests: libopencv-dev, GoogleTest, python3), without installing anything: apt-get plans both against a
# stand-in dpkg status that holds only a minimal base system (the Priority: required packages of this machine plus apt,
# closed over their dependencies: ~90 packages, as debootstrap's minbase or the debian:12 image) and an empty archive
# cache. Figures in docs/quickstart.md, "What apt installs". Usage: scripts/experiments/apt_sizes.sh [WORK_DIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
W=${1:-$(mktemp -d)}
mkdir -p "$W/archives/partial"
python3 - "$W/status" <<'PY'
import re, sys
stanzas = {}
for s in open('/var/lib/dpkg/status').read().split('\n\n'):
    m = re.search(r'^Package: (\S+)', s, re.M)
    if m and 'Status: install ok installed' in s:
        stanzas[m.group(1)] = s
def deps(s):
    for field in ('Depends', 'Pre-Depends'):
        m = re.search(r'^' + field + r': (.*)$', s, re.M)
        if m:
            for alt in m.group(1).split(','):
                yield [a.strip().split()[0].split(':')[0] for a in alt.split('|')]
todo = [p for p, s in stanzas.items() if re.search(r'^Priority: required$', s, re.M)] + ['apt']
keep = set()
while todo:
    p = todo.pop()
    if p in keep or p not in stanzas:
        continue
    keep.add(p)
    for alts in deps(stanzas[p]):
        todo.extend([a for a in alts if a in stanzas][:1])
open(sys.argv[1], 'w').write('\n\n'.join(stanzas[p] for p in sorted(keep)) + '\n\n')
print(f'base system: {len(keep)} packages')
PY
# The package lists install_deps.sh would install (its own arrays, so the two cannot drift apart).
eval "$(sed -n '/^PKGS=(/,/^FULL=(/p' scripts/install_deps.sh)"
APT=(-o Dir::State::status="$W/status" -o Debug::NoLocking=1 -o Dir::Cache::archives="$W/archives")
n=0
plan() {
  local name=$1
  shift
  local list="$W/plan$((++n)).txt"
  apt-get install --dry-run --no-install-recommends "${APT[@]}" "$@" 2>/dev/null | awk '/^Inst/{print $2}' >"$list"
  local sizes
  sizes=$(xargs apt-cache show --no-all-versions <"$list" |
    awk '/^Size:/{s += $2} /^Installed-Size:/{i += $2}
         END{printf "%.0f MB to download, %.0f MB installed", s / 1e6, i / 1024}')
  printf '%-34s %4d packages, %s\n' "$name" "$(wc -l <"$list")" "$sizes"
}
plan "full (scripts/test.sh)" "${PKGS[@]}" "${FULL[@]}"
plan "minimal (scripts/quickstart.sh)" "${PKGS[@]}" "${MINIMAL[@]}"
plan "minimal without ROS bags" $(printf '%s\n' "${PKGS[@]}" | grep -v -e ros -e sensor-msgs -e console-bridge) \
  "${MINIMAL[@]}"
plan "libopencv-dev alone" libopencv-dev
plan "the six modules alone" "${OPENCV_MODULES[@]}"
