#!/bin/sh
# check_format.sh - the C and C++ sources as clang-format writes them (.clang-format): every file
# that differs is named with its first differing lines, and the check fails. `make format`
# rewrites them.
cd "$(dirname "$0")/.." || exit 1
if ! command -v clang-format >/dev/null 2>&1; then
  echo "check_format: clang-format is not installed (make deps installs Debian's clang-format)"
  exit 1
fi
files=$(git ls-files '*.c' '*.h' '*.cpp' 2>/dev/null) ||
  files=$(find app bench fuzz include python src tests -name '*.[ch]' -o -name '*.cpp')
# shellcheck disable=SC2086
clang-format --dry-run --Werror $files || exit 1
echo "check_format: $(echo "$files" | wc -w) files as clang-format writes them"
