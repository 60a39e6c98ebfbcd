#!/usr/bin/env bash
# Sizes and load times of morphkit's animation outputs (the README's "Output formats" table).
#
# Usage: tools/measure-outputs.sh MORPHKIT_BINARY DATA_DIR OUT_DIR [OLD_MORPHKIT_BINARY]
# Writes a 10-frame camel (horse-01…10 transferred onto the camel) and a 2 100-frame linear
# blend of the 420-vertex cragl tube as GLB (one target per frame with and without normals,
# with --sparse-targets, --quantize and both; the tube also as a compact clip), PC2 and USDA,
# and, with
# OLD_MORPHKIT_BINARY, the GLB of an older build for comparison; prints their sizes, then the
# three.js load times (tools/threejs-check, best of 3) and, when blender is on PATH, the
# Blender import times (tools/blender-check).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="$1" data="$2" out="$3" old="${4:-}"
mkdir -p "$out"
cd "$out"
h="$data/sumner-horse-camel" c="$data/cragl-bending-cylinder"
"$bin" transfer --source-ref "$h/horse-reference.obj.gz" --source "$h/horse-[01][0-9].obj.gz" \
  --target "$h/camel-reference.obj.gz" --markers "$h/markers-horse-camel.json" --out camel10 --force
"$bin" blend --base "$c/cylinder-rest.obj" --target "$c/cylinder-bend-4.obj" --frames 2100 \
  --linear --out tube2100 --force
# One target per frame (the tube is longer than --max-targets, so by default it would be a
# compact clip: measured separately below as tube2100-compact*.glb).
for n in camel10 tube2100; do
  [ -n "$old" ] && "$old" convert "$n" "$n-old.glb" 2>/dev/null
  "$bin" convert "$n" --per-frame-targets "$n.glb" 2>/dev/null
  "$bin" convert "$n" --per-frame-targets --no-normals "$n-no-normals.glb" 2>/dev/null
  "$bin" convert "$n" --per-frame-targets --sparse-targets "$n-sparse.glb" 2>/dev/null
  "$bin" convert "$n" --per-frame-targets --quantize "$n-quantized.glb" 2>/dev/null
  "$bin" convert "$n" --per-frame-targets --quantize --sparse-targets "$n-packed.glb" 2>/dev/null
  "$bin" convert "$n" "$n.pc2" 2>/dev/null
  "$bin" convert "$n" "$n.usda" 2>/dev/null
done
"$bin" convert tube2100 tube2100-compact.glb 2>/dev/null
"$bin" convert tube2100 --quantize tube2100-compact-quantized.glb 2>/dev/null
ls -l ./*.glb ./*.pc2 ./*.usda | awk '{printf "%12d  %s\n", $5, $9}'
(cd "$here/threejs-check" && npm ci --no-audit --no-fund --loglevel=error)
for g in ./*.glb; do
  frames="${g%.glb}"; frames="${frames%-old}"; frames="${frames%-no-normals}"
  frames="${frames%-sparse}"; frames="${frames%-quantized}"; frames="${frames%-packed}"
  frames="${frames%-compact}"
  # Quantized files are within 2.7e-5 of the diagonal, not the default 1e-6; compact clips
  # within their tolerance (1e-3).
  tol=1e-6
  case "$g" in *-quantized.glb|*-packed.glb) tol=1e-4 ;; esac
  case "$g" in *-compact*.glb) tol=1.001e-3 ;; esac
  best=""
  for _ in 1 2 3; do
    t=$(node "$here/threejs-check/check.mjs" --tol "$tol" "$g" "$frames" | node -e \
      'let s="";process.stdin.on("data",d=>s+=d).on("end",()=>{const r=JSON.parse(s);console.log(Math.round(r.loadMs)+(r.ok?"":" (does not play: "+r.problems[0]+")"))})' || true)
    best="$best $t"
  done
  echo "three.js $g: load ms$best"
  if command -v blender >/dev/null 2>&1; then
    last=$(ls "$frames"/frame_*.obj | tail -1)
    blender -b --factory-startup --python "$here/blender-check/import_glb.py" -- "$g" "$last" 2>&1 | grep BLENDER || true
  fi
done
