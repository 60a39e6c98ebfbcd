"""Imports a GLB morphkit wrote into Blender headless and checks the last frame.

Usage: blender -b --factory-startup --python import_glb.py -- FILE.glb LAST_FRAME.obj

Prints one line: the import time, the mesh objects and shape keys, the last animation frame,
and the largest coordinate error of the visible mesh at that frame against LAST_FRAME.obj (glTF
+Y up is Blender's +Z up). Debian's blender 3.4 is built without USD, so it cannot import .usda.
"""
import bpy, sys, time
import numpy
if not hasattr(numpy, "bool"):
    numpy.bool = bool  # Debian blender 3.4 glTF importer vs numpy >= 1.24
argv = sys.argv[sys.argv.index("--") + 1:]
glb, last_obj, fps = argv[0], argv[1], 24
bpy.ops.wm.read_factory_settings(use_empty=True)
t0 = time.time()
bpy.ops.import_scene.gltf(filepath=glb)
load = time.time() - t0
objs = [o for o in bpy.context.scene.objects if o.type == 'MESH']
keys = sum(len(o.data.shape_keys.key_blocks) - 1 for o in objs if o.data.shape_keys)
actions = bpy.data.actions
end = max(int(round(a.frame_range[1])) for a in actions)
sc = bpy.context.scene
sc.render.fps = fps
sc.frame_set(end)
dg = bpy.context.evaluated_depsgraph_get()
exp = [tuple(map(float, l.split()[1:4])) for l in open(last_obj) if l.startswith('v ')]
best = None
for o in objs:
    if o.matrix_world.to_scale().x == 0:
        continue
    ev = o.evaluated_get(dg)
    m = ev.to_mesh()
    # glTF is +Y up; Blender converts to +Z up: (x, y, z)_gltf = (x, z, -y)_blender
    err = max(max(abs(v.co.x - e[0]), abs(v.co.z - e[1]), abs(-v.co.y - e[2])) for v, e in zip(m.vertices, exp))
    ev.to_mesh_clear()
    best = err if best is None else min(best, err)
print(f"BLENDER {glb}: import {load:.2f} s, {len(objs)} mesh objects, {keys} shape keys, last frame {end}, max error at the last frame {best:.2e}")
