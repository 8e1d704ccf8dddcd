#!/usr/bin/env bash
# The format check: every tracked .cpp/.h must be what clang-format makes of it with the root .clang-format.
# Exit 0 when all are, 1 (listing each file and line) otherwise. Fix with: clang-format -i FILES.
# Installs clang-format when it is missing (Debian). CLANG_FORMAT overrides the binary.
set -euo pipefail
cd "$(dirname "$0")/.."
CLANG_FORMAT=${CLANG_FORMAT:-clang-format}
command -v "$CLANG_FORMAT" >/dev/null 2>&1 || scripts/install_deps.sh clang-format
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -d '' files < <(git ls-files -z -- '*.cpp' '*.h')
else # a tarball of the tree: everything but build folders
  mapfile -d '' files < <(find . \( -name 'build*' -o -name '.git' \) -prune -o \( -name '*.cpp' -o -name '*.h' \) \
    -type f -print0)
fi
"$CLANG_FORMAT" --dry-run -Werror "${files[@]}"
echo "check_format: ${#files[@]} files formatted ($("$CLANG_FORMAT" --version | head -1))"
