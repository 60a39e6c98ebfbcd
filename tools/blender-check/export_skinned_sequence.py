"""Exports a skinned animation the way a DCC hands one on (issue 56: compact clips of a
DCC-exported sequence): the cylinder OBJ becomes a mesh with a Smart UV Project map, smooth
shading and a material, skinned to a two-bone armature (weights blended across the middle),
whose upper bone bends and twists back and forth; Blender's own OBJ exporter writes one file
per frame (`export_animation`), with UVs and normals, as a TD bakes a rig for another tool.

    blender -b --factory-startup --python export_skinned_sequence.py -- REST.obj OUT_DIR FRAMES

Positions keep the OBJ's axes (the importer's rotation is applied, and the exporter writes
Blender's Z-up as the file's Y-up again), so frame 1 equals REST.obj up to the exporter's
rounding. Files are OUT_DIR/skinned1.obj … skinnedFRAMES.obj, unpadded, as Blender names
them (morphkit orders them by frame number).
"""
import math
import os
import sys

import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
rest_path, out_dir, frames = args[0], args[1], int(args[2])
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)

if hasattr(bpy.ops.wm, "obj_import"):
    bpy.ops.wm.obj_import(filepath=rest_path)
else:
    bpy.ops.import_scene.obj(filepath=rest_path, split_mode="OFF")
body = bpy.context.selected_objects[0]
bpy.context.view_layer.objects.active = body
bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
mesh = body.data
for poly in mesh.polygons:
    poly.use_smooth = True
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.uv.smart_project()
bpy.ops.object.mode_set(mode="OBJECT")
mesh.materials.append(bpy.data.materials.new("skin"))

# The long axis of the bounding box is the bones' axis.
lo = Vector([min(v.co[k] for v in mesh.vertices) for k in range(3)])
hi = Vector([max(v.co[k] for v in mesh.vertices) for k in range(3)])
axis = max(range(3), key=lambda k: hi[k] - lo[k])
centre = (lo + hi) / 2
start, end = centre.copy(), centre.copy()
start[axis], end[axis] = lo[axis], hi[axis]
middle = (start + end) / 2

bpy.ops.object.armature_add(enter_editmode=True, location=(0, 0, 0))
rig = bpy.context.object
bones = rig.data.edit_bones
lower = bones[0]
lower.name = "lower"
lower.head, lower.tail = start, middle
upper = bones.new("upper")
upper.head, upper.tail = middle, end
upper.parent = lower
upper.use_connect = True
bpy.ops.object.mode_set(mode="OBJECT")

# Linear blend skinning weights: the upper bone's share rises smoothly across the middle fifth.
groups = {name: body.vertex_groups.new(name=name) for name in ("lower", "upper")}
length = hi[axis] - lo[axis]
for v in mesh.vertices:
    x = (v.co[axis] - middle[axis]) / (0.2 * length) + 0.5
    x = min(1.0, max(0.0, x))
    w = x * x * (3 - 2 * x)
    groups["upper"].add([v.index], w, "REPLACE")
    groups["lower"].add([v.index], 1 - w, "REPLACE")
modifier = body.modifiers.new("skin", "ARMATURE")
modifier.object = rig
body.parent = rig

# The upper bone bends by up to 100° about a bone-local axis and twists by up to 60°: up,
# down and up again over the clip (the last frame differs from the first).
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, frames
pose = rig.pose.bones["upper"]
pose.rotation_mode = "XYZ"
for f in range(1, frames + 1):
    s = math.sin(1.5 * math.pi * (f - 1) / (frames - 1)) ** 2
    pose.rotation_euler = (math.radians(100) * s, math.radians(60) * s, 0.0)
    pose.keyframe_insert("rotation_euler", frame=f)

os.makedirs(out_dir, exist_ok=True)
bpy.ops.object.select_all(action="DESELECT")
body.select_set(True)
bpy.context.view_layer.objects.active = body
bpy.ops.wm.obj_export(
    filepath=os.path.join(out_dir, "skinned.obj"),
    export_animation=True,
    start_frame=1,
    end_frame=frames,
    export_selected_objects=True,
    export_uv=True,
    export_normals=True,
    export_materials=False,
    apply_modifiers=True,
)
