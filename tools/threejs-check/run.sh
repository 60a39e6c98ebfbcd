#!/usr/bin/env bash
# End-to-end viewer test (issue 15): GLBs that the morphkit CLI writes play in three.js
# (GLTFLoader + AnimationMixer) in headless Chromium, key by key equal to the OBJ frames, and
# render (SwiftShader WebGL2) a first and a last frame that are drawn and differ.
#
# Usage: tools/threejs-check/run.sh MORPHKIT_BINARY DATA_DIR OUT_DIR
#   DATA_DIR is the shared data (cragl-bending-cylinder, sumner-horse-gallop); OUT_DIR receives
#   the GLBs, their OBJ frames, screenshots (OUT_DIR/shots) and results.jsonl.
# Needs node/npm and Debian's chromium (or $CHROMIUM); fails with a message when either is
# missing. three and playwright-core come from the npm registry (package-lock.json); no
# browser is downloaded.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
if [ $# -ne 3 ]; then
  echo "usage: $0 MORPHKIT_BINARY DATA_DIR OUT_DIR" >&2
  exit 2
fi
bin="$1" data="$2" out="$3"
chromium="${CHROMIUM:-/usr/bin/chromium}"
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "threejs-check: node and npm are missing; install them (apt-get install -y nodejs npm)" >&2
  exit 1
fi
if [ ! -x "$chromium" ]; then
  echo "threejs-check: Chromium is missing at $chromium; install Debian's chromium (apt-get install -y chromium) or set CHROMIUM" >&2
  exit 1
fi
(cd "$here" && npm ci --no-audit --no-fund --loglevel=error)
mkdir -p "$out"
cyl="$data/cragl-bending-cylinder"
# A 2 100-frame blend of a 420-vertex tube: more morph targets than one WebGL2 mesh holds.
"$bin" blend --base "$cyl/cylinder-rest.obj" --target "$cyl/cylinder-bend-4.obj" --frames 2100 \
  --linear --out "$out/tube2100" --force
# Longer than --max-targets (200): a compact clip by default (one target at per-frame weights:
# the linear blend is exact in it), and one target per frame split into 11 meshes on request.
"$bin" convert "$out/tube2100" "$out/tube2100.glb"
"$bin" convert "$out/tube2100" --per-frame-targets "$out/tube2100-split.glb"
# A physical blend as OBJ frames, and the same frames as GLB.
"$bin" blend --base "$cyl/cylinder-rest.obj" --target "$cyl/cylinder-bend-4.obj" --frames 24 \
  --out "$out/bend24" --force
"$bin" convert "$out/bend24" "$out/bend24.glb"
# A real sequence converted from OBJ files.
"$bin" convert "$data/sumner-horse-gallop/horse-gallop-*.obj.gz" "$out/horse-gallop" --force
"$bin" convert "$out/horse-gallop" "$out/horse-gallop.glb"
node "$here/check.mjs" --shots "$out/shots" \
  "$out/tube2100.glb" "$out/tube2100" \
  "$out/tube2100-split.glb" "$out/tube2100" \
  "$out/bend24.glb" "$out/bend24" \
  "$out/horse-gallop.glb" "$out/horse-gallop" | tee "$out/results.jsonl"
# The physical frames as a compact clip on request (--clip-tolerance): a few targets whose
# fitted normal deltas shade each frame, every frame within the tolerance as played.
"$bin" convert "$out/bend24" --clip-tolerance 1e-3 "$out/bend24-compact.glb"
node "$here/check.mjs" --tol 1.001e-3 --shots "$out/shots" "$out/bend24-compact.glb" "$out/bend24" \
  | tee -a "$out/results.jsonl"
# The same 2 100 frames quantized (KHR_mesh_quantization, dequantized by the node transform) with
# sparse morph targets: within the quantization error (2.7e-5 of the diagonal by construction).
"$bin" convert "$out/tube2100" --quantize --sparse-targets "$out/tube2100-packed.glb"
node "$here/check.mjs" --tol 1e-4 --shots "$out/shots" "$out/tube2100-packed.glb" "$out/tube2100" \
  | tee -a "$out/results.jsonl"
# The horse gallop quantized and meshopt-compressed (--meshopt, EXT_meshopt_compression: 10.1 MB
# → 5.9 MB), which GLTFLoader decodes with three's MeshoptDecoder.
"$bin" --quantize --meshopt convert "$out/horse-gallop" "$out/horse-gallop-meshopt.glb"
node "$here/check.mjs" --tol 1e-4 --shots "$out/shots" "$out/horse-gallop-meshopt.glb" \
  "$out/horse-gallop" | tee -a "$out/results.jsonl"
# A baked rig (issue 56): the cylinder with two targets (bend-4 and pose1-4, through a frame
# sequence), baked with in-betweens and combination shapes; three.js plays it through the
# JavaScript evaluation in docs/bake.md (check.mjs --bake loads that block itself), row by row
# equal to the library's evaluation that `bake --check-frames` writes. The same rows compared
# with the linear blend must fail: the check sees what the mapping adds.
mkdir -p "$out/bake-seq"
cp "$cyl/cylinder-rest.obj" "$out/bake-seq/frame_0000.obj"
cp "$cyl/cylinder-bend-4.obj" "$out/bake-seq/frame_0001.obj"
cp "$cyl/cylinder-pose1-4.obj" "$out/bake-seq/frame_0002.obj"
"$bin" convert "$out/bake-seq" "$out/bake-rig.glb" --force
printf 'frame_0001,frame_0002\n0.5,0\n0,0.7\n0.5,0.5\n1,1\n0.8,0.3\n0.3,0.9\n1.2,0.9\n' >"$out/bake-rows.csv"
"$bin" bake --rig "$out/bake-rig.glb" --out "$out/bake-baked.glb" --check "$out/bake-rows.csv" \
  --check-frames "$out/bake-played" --force
node "$here/check.mjs" --bake "$out/bake-rows.csv" --shots "$out/shots" \
  "$out/bake-baked.glb" "$out/bake-played" | tee -a "$out/results.jsonl"
"$bin" blend --rig "$out/bake-rig.glb" --linear --weights-file "$out/bake-rows.csv" \
  --out "$out/bake-linear" --force
if node "$here/check.mjs" --bake "$out/bake-rows.csv" "$out/bake-baked.glb" "$out/bake-linear" \
  >"$out/bake-linear.jsonl"; then
  echo "threejs-check: the baked rig played like the linear blend; the bake check is broken" >&2
  exit 1
fi
# An artist's own asset (issue 37): Blender exports the cylinder rig flat shaded (every triangle
# its own vertices) with a UV map, a material and a shape key, and again smooth with Smart UV
# Project seams and two materials, one with an image texture (two primitives); `blend --rig`
# solves each welded and adds the physical clip to that asset, which three.js plays key by key
# like the OBJ frames of the same blend (the textured one's shots show the texture), and so
# does the textured asset's `--interactive` clip. Needs
# Blender (CI installs it); skipped with a message without it.
if command -v blender >/dev/null 2>&1; then
  # The cylinder's OBJ faces name texture coordinates the file does not have, and Blender's
  # importer drops such faces: Blender gets plain copies (through PLY, so no OBJ record stays).
  for shape in rest bend-4; do
    "$bin" convert "$cyl/cylinder-$shape.obj" "$out/plain-$shape.ply" --force 2>/dev/null
    "$bin" convert "$out/plain-$shape.ply" "$out/plain-$shape.obj" --force 2>/dev/null
  done
  printf 'bend\n0\n0.25\n0.5\n0.75\n1\n' >"$out/artist-weights.csv"
  for mode in flat artist; do
    blender -b --factory-startup --python "$here/../blender-check/export_split_rig.py" -- \
      "$out/plain-rest.obj" "$out/plain-bend-4.obj" "$out/$mode-rig.glb" $mode apply >/dev/null
    "$bin" blend --rig "$out/$mode-rig.glb" --weights-file "$out/artist-weights.csv" \
      --per-frame-targets --out "$out/$mode-physical.glb" --force
    "$bin" blend --rig "$out/$mode-rig.glb" --weights-file "$out/artist-weights.csv" \
      --out "$out/$mode-physical" --force
  done
  # The compact physical clip (issue 56, the default of `blend --rig`): the asset's target at
  # the clip's weights plus corrective targets, within --clip-tolerance (1e-3 of the diagonal)
  # of the solve in every frame; a 5-key clip and a 300-key one (a bend that rises, falls
  # and rises again to 1, at 30 fps; first and last frames differ, as the check wants).
  "$bin" blend --rig "$out/artist-rig.glb" --weights-file "$out/artist-weights.csv" \
    --out "$out/artist-compact.glb" --force
  awk 'BEGIN { print "bend"; for (k = 0; k < 300; k++) { s = sin(3.14159265 * 2.5 * k / 299); printf "%.6f\n", s * s } }' \
    >"$out/long-weights.csv"
  "$bin" blend --rig "$out/artist-rig.glb" --weights-file "$out/long-weights.csv" --fps 30 \
    --out "$out/long-compact.glb" --force
  "$bin" blend --rig "$out/artist-rig.glb" --weights-file "$out/long-weights.csv" --fps 30 \
    --out "$out/long-compact" --force
  node "$here/check.mjs" --tol 1.001e-3 --shots "$out/shots" \
    "$out/artist-compact.glb" "$out/artist-physical" \
    "$out/long-compact.glb" "$out/long-compact" | tee -a "$out/results.jsonl"
  # A bake of the artist's asset (Blender-exported: UV seams, two materials, a texture), with
  # in-betweens where the bend needs them; three.js plays it through docs/bake.md's evaluation
  # row by row like the library's, past 1 included.
  printf 'bend\n0.1\n0.3\n0.55\n0.8\n1\n1.15\n' >"$out/artist-bake-rows.csv"
  "$bin" bake --rig "$out/artist-rig.glb" --out "$out/artist-baked.glb" \
    --check "$out/artist-bake-rows.csv" --check-frames "$out/artist-bake-played" --force
  node "$here/check.mjs" --bake "$out/artist-bake-rows.csv" --shots "$out/shots" \
    "$out/artist-baked.glb" "$out/artist-bake-played" | tee -a "$out/results.jsonl"
  # Smaller correctives: 16-bit (--quantize, KHR_mesh_quantization), and meshopt-compressed
  # like their input when gltfpack (tools/gltf-assets) packs the rig (-c, unquantized so that
  # the node keeps no dequantization transform and the OBJ frames stay comparable).
  "$bin" --quantize blend --rig "$out/artist-rig.glb" --weights-file "$out/long-weights.csv" \
    --fps 30 --out "$out/long-quantized.glb" --force
  pairs=("$out/long-quantized.glb" "$out/long-compact")
  gltfpack="$here/../gltf-assets/node_modules/.bin/gltfpack"
  if [ -x "$gltfpack" ]; then
    "$gltfpack" -i "$out/artist-rig.glb" -o "$out/artist-meshopt.glb" -c -noq -kn -km -ke >/dev/null
    "$bin" --quantize blend --rig "$out/artist-meshopt.glb" --weights-file "$out/long-weights.csv" \
      --fps 30 --out "$out/long-meshopt.glb" --force
    "$bin" blend --rig "$out/artist-meshopt.glb" --weights-file "$out/long-weights.csv" \
      --fps 30 --out "$out/long-meshopt" --force
    pairs+=("$out/long-meshopt.glb" "$out/long-meshopt")
  else
    echo "threejs-check: no gltfpack (npm ci in tools/gltf-assets); the meshopt clip is skipped" >&2
  fi
  # A transfer onto the artist's asset (issue 56): 300 frames do not fit beside its target
  # under --max-targets, so they go in as a compact clip (the asset's target at weight 0 and a
  # few targets of the frames' displacements), played key by key like the transfer's OBJ
  # frames in the asset's layout. The source is the asset's own linear clip (its base as the
  # source reference, markers on the same vertices); onto gltfpack's copy of the asset (which
  # welds and reorders the vertices: the source is that copy's clip) the clip is stored 16-bit
  # and meshopt-compressed like the copy.
  printf '{"pairs": [[0, 0], [100, 100], [200, 200], [300, 300], [400, 400]]}\n' \
    >"$out/transfer-markers.json"
  targets=(artist-rig)
  [ -x "$gltfpack" ] && targets+=(artist-meshopt)
  for asset in "${targets[@]}"; do
    name="transfer-${asset#artist-}"
    "$bin" blend --rig "$out/$asset.glb" --weights-file "$out/long-weights.csv" --linear \
      --out "$out/$name-source.pc2" --force
    transfer=(transfer --source-ref "$out/$asset.glb" --source "$out/$name-source.pc2"
      --target "$out/$asset.glb" --markers "$out/transfer-markers.json" --fps 30 --force)
    "$bin" --quantize "${transfer[@]}" --out "$out/$name.glb"
    "$bin" "${transfer[@]}" --out "$out/$name"
    pairs+=("$out/$name.glb" "$out/$name")
  done
  # A DCC-exported sequence (issue 56): Blender skins the cylinder to a two-bone armature that
  # bends and twists, and its OBJ exporter writes 240 unpadded frames (skinned1.obj …
  # skinned240.obj, played in frame order); more frames than --max-targets, so `convert`
  # writes a compact clip, 16-bit with --quantize (and meshopt-compressed with --meshopt),
  # played like the same frames as OBJ.
  blender -b --factory-startup --python "$here/../blender-check/export_skinned_sequence.py" -- \
    "$out/plain-rest.obj" "$out/skinned-seq" 240 >/dev/null
  "$bin" convert "$out/skinned-seq" "$out/skinned" --force
  "$bin" convert "$out/skinned-seq" "$out/skinned.glb" --force
  "$bin" --quantize convert "$out/skinned-seq" "$out/skinned-quantized.glb" --force
  "$bin" --quantize --meshopt convert "$out/skinned-seq" "$out/skinned-meshopt.glb" --force
  pairs+=("$out/skinned.glb" "$out/skinned" "$out/skinned-quantized.glb" "$out/skinned"
    "$out/skinned-meshopt.glb" "$out/skinned")
  node "$here/check.mjs" --tol 1.001e-3 --shots "$out/shots" "${pairs[@]}" \
    | tee -a "$out/results.jsonl"
  # The interactive mode (issue 38) on the textured asset: the clip a TD bakes from the slider
  # previews plays like the OBJ frames of the same interactive blend.
  "$bin" blend --rig "$out/artist-rig.glb" --weights-file "$out/artist-weights.csv" \
    --interactive --per-frame-targets --out "$out/artist-interactive.glb" --force
  "$bin" blend --rig "$out/artist-rig.glb" --weights-file "$out/artist-weights.csv" \
    --interactive --out "$out/artist-interactive" --force
  node "$here/check.mjs" --shots "$out/shots" "$out/flat-physical.glb" "$out/flat-physical" \
    "$out/artist-physical.glb" "$out/artist-physical" \
    "$out/artist-interactive.glb" "$out/artist-interactive" | tee -a "$out/results.jsonl"
else
  echo "threejs-check: no blender on the PATH; the artist's-asset check is skipped" >&2
fi
# The check must be able to fail: the same 2 100 frames in one mesh (no split) stay at frame 0
# in WebGL (texSubImage3D out of range), and the check has to say so.
"$bin" convert "$out/tube2100" --max-targets 0 "$out/tube2100-one-mesh.glb"
if node "$here/check.mjs" "$out/tube2100-one-mesh.glb" "$out/tube2100" >"$out/one-mesh.jsonl"; then
  echo "threejs-check: the unsplit 2 100-target GLB passed, but WebGL cannot play it; the check is broken" >&2
  exit 1
fi
echo "threejs-check: all GLBs play to their last frame; the unsplit one is caught as expected"
