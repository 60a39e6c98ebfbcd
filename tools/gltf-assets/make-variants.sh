#!/bin/sh
# Writes the variants of a glTF/GLB file that exporters produce, for morphkit's reader tests:
#
#   quantized.glb            gltfpack (KHR_mesh_quantization: integer positions and deltas,
#                            the dequantization on the node)
#   meshopt.glb              gltfpack -c (quantized and meshopt-compressed)
#   meshopt-noq.glb          gltfpack -c -noq (meshopt-compressed floats)
#   sparse.glb               gltf-transform sparse (sparse accessors where >= 1/3 are zero)
#   transform-meshopt.glb    gltf-transform meshopt (quantized, meshopt with filters)
#
# Usage: sh make-variants.sh IN.glb OUTDIR   (after `npm ci` in this directory)
# Animations are kept as they are (-af 0: no resampling; -ac: keep constant tracks).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
bin="$here/node_modules/.bin"
in=$1
out=$2
mkdir -p "$out"
"$bin/gltfpack" -i "$in" -o "$out/quantized.glb" -af 0 -ac
"$bin/gltfpack" -i "$in" -o "$out/meshopt.glb" -c -af 0 -ac
"$bin/gltfpack" -i "$in" -o "$out/meshopt-noq.glb" -c -noq -af 0 -ac
"$bin/gltf-transform" sparse "$in" "$out/sparse.glb" >/dev/null
"$bin/gltf-transform" meshopt "$in" "$out/transform-meshopt.glb" >/dev/null
