# Sourced (from the repository's root) by the MCAP experiments that replay files written by the independent writers
# (mcap_compressed_ape.sh, mcap_jpeg_paired_ape.sh): BIN is $OVTON_BIN, else build/ovton (built when missing); TOOLS is
# scripts/mcap_tools with its npm packages installed.
BIN=${OVTON_BIN:-$PWD/build/ovton}
TOOLS=$PWD/scripts/mcap_tools
if [ ! -x "$BIN" ]; then
  [ -z "${OVTON_BIN:-}" ] || { echo "OVTON_BIN=$OVTON_BIN is not executable" >&2; exit 1; }
  scripts/build.sh
fi
[ -d "$TOOLS/node_modules/@mcap/core" ] || npm ci --prefix "$TOOLS" --no-audit --no-fund
