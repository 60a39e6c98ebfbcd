"""Imports a .usda animation written by morphkit with Blender's own USD importer (the `bpy`
module from PyPI: Debian's Blender 3.4 is built without USD) and compares every frame with
the OBJ frames of the same run.

    python import_usd.py ANIM.usda FRAMES_DIR

Checks: the imported scene covers the file's frame range (startTimeCode..endTimeCode), the
mesh has the frames' vertex count, and at every frame the evaluated vertices (Blender applies
the time-sampled points through a Mesh Sequence Cache modifier, in the file's up axis
converted to Blender's Z-up) match the OBJ frame within 1e-6 of the bounding-box diagonal.
Prints one line per check; exits 1 on a failure, 2 when bpy is missing.
"""

import pathlib
import sys

try:
    import bpy
except ImportError:
    print("import_usd.py: the bpy module is missing; pip install bpy", file=sys.stderr)
    sys.exit(2)
import numpy as np


def read_obj(path):
    v = [list(map(float, line.split()[1:4])) for line in open(path) if line.startswith("v ")]
    return np.array(v)


def main():
    usda, frames_dir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    frames = [read_obj(p) for p in sorted(frames_dir.glob("frame_*.obj"))]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.usd_import(filepath=str(usda), set_frame_range=True)
    scene = bpy.context.scene
    meshes = [o for o in scene.objects if o.type == "MESH"]
    ok = True
    n_frames = scene.frame_end - scene.frame_start + 1
    print(f"frames: file {len(frames)}, Blender {scene.frame_start}..{scene.frame_end} ({n_frames})")
    ok &= n_frames == len(frames) and len(meshes) == 1
    obj = meshes[0]
    diag = np.linalg.norm(frames[0].max(0) - frames[0].min(0))
    worst = 0.0
    for k, ref in enumerate(frames):
        scene.frame_set(scene.frame_start + k)
        ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mw = np.array(ev.matrix_world)
        co = np.array([v.co[:] for v in ev.data.vertices])
        world = co @ mw[:3, :3].T + mw[:3, 3]
        # USD Y-up → Blender Z-up: (x, y, z) → (x, -z, y).
        ref_z = np.stack([ref[:, 0], -ref[:, 2], ref[:, 1]], axis=1)
        if world.shape != ref.shape:
            print(f"frame {k}: {world.shape[0]} vertices, expected {ref.shape[0]}")
            ok = False
            continue
        worst = max(worst, float(np.abs(world - ref_z).max()) / diag)
    print(f"positions: worst {worst:.2e} of the diagonal (bound 1e-6)")
    ok &= worst <= 1e-6
    print("USD import: OK" if ok else "USD import: FAILED")
    sys.exit(0 if ok else 1)


main()
