#!/usr/bin/env python3
"""Validates .usda layers morphkit writes with Pixar's USD (the `usd-core` package from PyPI).

Usage: python3 check.py [--frames N] [--blendshapes NAME,NAME,...] FILE.usda ...
(an option applies to the files after it)

For each file: opens the stage, runs the USD validators (UsdUtils.ComplianceChecker where
usd-core still has it, else every validator of UsdValidation, its successor), and checks the
stage metadata morphkit writes (upAxis, metersPerUnit, timeCodesPerSecond, start/end time
codes). With --frames N the first Mesh must have N time samples of `points`, all with as many
points as the mesh. With --blendshapes the SkelRoot's mesh must bind those blend shapes, each
a valid UsdSkel BlendShape. Prints one line per file, `FILE: N errors`, then the errors; exits
1 when any file has errors, 2 on bad usage or when `pxr` is missing.
"""
import sys

try:
    from pxr import Usd, UsdGeom, UsdSkel
except ImportError:
    print("check.py: the pxr module is missing; pip install usd-core", file=sys.stderr)
    sys.exit(2)


def validate(path, stage):
    errors = []
    try:
        from pxr import UsdUtils

        checker_cls = getattr(UsdUtils, "ComplianceChecker", None)
    except ImportError:
        checker_cls = None
    if checker_cls is not None:
        c = checker_cls(rootPackageOnly=False, skipVariants=False, verbose=False)
        c.CheckCompliance(path)
        errors += [f"compliance: {e}" for e in c.GetErrors() + c.GetFailedChecks()]
    else:
        from pxr import UsdValidation

        validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
        ctx = UsdValidation.ValidationContext(validators)
        for e in ctx.Validate(stage):
            if e.GetType() in (UsdValidation.ValidationErrorType.Error, UsdValidation.ValidationErrorType.Warn):
                errors.append(f"{e.GetName()}: {e.GetMessage()}")
    return errors


def check(path, frames, shapes):
    stage = Usd.Stage.Open(path)
    if stage is None:
        return [f"USD cannot open the file"]
    errors = validate(path, stage)
    if not stage.GetDefaultPrim():
        errors.append("no defaultPrim")
    if not stage.HasAuthoredMetadata("upAxis") or UsdGeom.GetStageUpAxis(stage) not in ("Y", "Z"):
        errors.append("no upAxis")
    if not stage.HasAuthoredMetadata("metersPerUnit"):
        errors.append("no metersPerUnit")
    meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    if not meshes:
        return errors + ["no Mesh prim"]
    mesh = meshes[0]
    n = len(mesh.GetPointsAttr().Get(Usd.TimeCode.EarliestTime()) or [])
    if sum(mesh.GetFaceVertexCountsAttr().Get() or []) != len(mesh.GetFaceVertexIndicesAttr().Get() or []):
        errors.append("faceVertexCounts do not add up to faceVertexIndices")
    if frames is not None:
        samples = mesh.GetPointsAttr().GetTimeSamples()
        if len(samples) != frames:
            errors.append(f"{len(samples)} points samples, expected {frames}")
        if stage.GetEndTimeCode() - stage.GetStartTimeCode() + 1 != frames:
            errors.append(f"time codes {stage.GetStartTimeCode()}..{stage.GetEndTimeCode()} for {frames} frames")
        if not stage.HasAuthoredTimeCodeRange() or stage.GetTimeCodesPerSecond() <= 0:
            errors.append("no time code range or timeCodesPerSecond")
        for t in samples:
            if len(mesh.GetPointsAttr().Get(t)) != n:
                errors.append(f"time {t}: point count differs")
                break
        if len(mesh.GetExtentAttr().GetTimeSamples()) != frames:
            errors.append("extent is not sampled per frame")
    if shapes is not None:
        binding = UsdSkel.BindingAPI(mesh.GetPrim())
        names = list(binding.GetBlendShapesAttr().Get() or [])
        if names != shapes:
            errors.append(f"blend shapes {names}, expected {shapes}")
        targets = binding.GetBlendShapeTargetsRel().GetTargets()
        for t in targets:
            bs = UsdSkel.BlendShape(stage.GetPrimAtPath(t))
            if not bs or len(bs.GetOffsetsAttr().Get() or []) != len(bs.GetPointIndicesAttr().Get() or []):
                errors.append(f"{t}: not a BlendShape with matching offsets and pointIndices")
        if len(targets) != len(shapes):
            errors.append(f"{len(targets)} blend shape targets for {len(shapes)} names")
    return errors


def main(argv):
    files, frames, shapes, failed = [], None, None, False
    jobs = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--frames":
            frames = int(argv[i + 1]); i += 2; continue
        if a == "--blendshapes":
            shapes = argv[i + 1].split(","); i += 2; continue
        jobs.append((a, frames, shapes)); i += 1
    if not jobs:
        print(__doc__, file=sys.stderr)
        return 2
    for path, fr, sh in jobs:
        errors = check(path, fr, sh)
        print(f"{path}: {len(errors)} errors")
        for e in errors:
            print(f"  error: {e}")
        failed |= bool(errors)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
