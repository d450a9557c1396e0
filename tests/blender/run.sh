#!/bin/sh
# run.sh - ctest blender_addon: a short run (tests/blender/scene.json, a cube of material points
# and a bunny with particle domains and its embedded surface), then Blender, headless, imports
# it with the add-on and checks it (tests/blender/check_addon.py).
#
#   run.sh MPM SOURCE_DIR
set -eu
mpm=$1 src=$2
command -v blender >/dev/null || {
  echo "blender_addon: no blender on PATH (Debian's blender: make deps-blender)" >&2
  exit 1
}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mpm-blender-check.XXXXXX")
trap '[ -n "${KEEP:-}" ] || rm -rf "$tmp"' EXIT INT TERM
"$mpm" run "$src/tests/blender/scene.json" -o "$tmp/run" --quiet
set +e
blender -b --factory-startup --python-exit-code 1 -P "$src/tests/blender/check_addon.py" \
  -- "$src" "$tmp/run" "$tmp/render.png" >"$tmp/blender.log" 2>&1
status=$?
set -e
# Blender's own chatter left out; the check's lines, and everything when it failed
if [ "$status" -eq 0 ]; then
  grep "check_addon" "$tmp/blender.log"
else
  cat "$tmp/blender.log"
  echo "blender_addon: Blender exited with $status" >&2
fi
exit "$status"
