#!/usr/bin/env bash
# Screenshot of the add-on's panels in a real (virtual-display) Blender window; see
# panel_screenshot.py. Usage: blender/tests/panel_screenshot.sh ADDON.zip DATA_DIR OUT.png
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export BLENDER_USER_CONFIG="$tmp/config" BLENDER_USER_SCRIPTS="$tmp/scripts"
for _ in 1 2; do  # the first run only turns the splash screen off
  xvfb-run -a -s "-screen 0 1280x1024x24" blender --python "$here/panel_screenshot.py" -- "$@"
done
test -s "$3"
