#!/usr/bin/env python3
"""Plays a baked UsdSkel rig (`morphkit bake --out FILE.usda`) through Pixar's UsdSkel API and
compares it with expected points: the check that UsdSkel evaluates the in-betweens as morphkit
does (docs/bake.md).

Usage: python3 bake_eval.py FILE.usda CASES.json
CASES.json: [{"weights": {"blendShapeName": weight, ...}, "points": [[x, y, z], ...]}, ...]
(blend shapes not named weigh 0). For each case: the mesh's points deformed by
UsdSkel.BlendShapeQuery (ComputeSubShapeWeights, then ComputeDeformedPoints) against `points`.
Prints `case K: ERROR` (largest vertex distance over the bounding-box diagonal of the rest
points) per case and `max ERROR`; exits 0, or 2 on bad usage or without `pxr`.
"""
import json
import sys

try:
    from pxr import Usd, UsdGeom, UsdSkel, Vt
except ImportError:
    print("bake_eval.py: the pxr module is missing; pip install usd-core", file=sys.stderr)
    sys.exit(2)


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    stage = Usd.Stage.Open(sys.argv[1])
    cases = json.load(open(sys.argv[2]))
    mesh = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    binding = UsdSkel.BindingAPI(mesh)
    query = UsdSkel.BlendShapeQuery(binding)
    names = list(binding.GetBlendShapesAttr().Get())
    rest = UsdGeom.Mesh(mesh).GetPointsAttr().Get()
    lo = [min(p[k] for p in rest) for k in range(3)]
    hi = [max(p[k] for p in rest) for k in range(3)]
    diag = sum((hi[k] - lo[k]) ** 2 for k in range(3)) ** 0.5
    indices = query.ComputeBlendShapePointIndices()
    offsets = query.ComputeSubShapePointOffsets()
    worst = 0.0
    for k, case in enumerate(cases):
        w = Vt.FloatArray([float(case["weights"].get(n, 0.0)) for n in names])
        sub_weights, shape_ids, sub_ids = query.ComputeSubShapeWeights(w)
        points = Vt.Vec3fArray(rest)
        query.ComputeDeformedPoints(sub_weights, shape_ids, sub_ids, indices, offsets, points)
        err = max(
            sum((points[v][c] - case["points"][v][c]) ** 2 for c in range(3)) ** 0.5
            for v in range(len(points))
        ) / diag
        worst = max(worst, err)
        print(f"case {k}: {err:.3e}")
    print(f"max {worst:.3e}")


main()
