"""Exports a rig the way an artist's Blender does (issue 37's test assets): two OBJ shapes of one
connectivity become one mesh with a shape key, a cylindrical UV map and a material, written as
GLB with its morph target. Shading `flat` (the default) makes the glTF exporter split every
triangle into its own three vertices; `smooth` keeps shared vertices except along the UV map's
seam, where the map wraps from u = 1 back to 0 (the split an artist's smooth, unwrapped
character gets); `artist` is smooth with Blender's Smart UV Project islands (seams wherever
the unwrap cuts) and two materials, the second with an image texture (a generated checker,
packed into the GLB), so the exporter also splits the mesh into two primitives at the
material border.

    blender -b --python export_split_rig.py -- BASE.obj TARGET.obj OUT.glb [flat|smooth|artist] [apply]

`apply` bakes the importer's object rotation (OBJ is Y-up) into the vertices, so the exported
node has no transform and the mesh's own space is the world's (what a viewer check compares).

Positions keep Blender's axes (`export_yup=False`), so they compare with the OBJ inputs.
"""
import math
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
base_path, target_path, out = args[:3]
mode = args[3] if len(args) > 3 else "flat"
smooth = mode in ("smooth", "artist")
apply = len(args) > 4 and args[4] == "apply"
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)


def load(path):
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=path)
    else:
        bpy.ops.import_scene.obj(filepath=path, split_mode="OFF")
    return bpy.context.selected_objects[0]


base = load(base_path)
target = load(target_path)
if apply:
    for o in (base, target):
        bpy.ops.object.select_all(action="DESELECT")
        o.select_set(True)
        bpy.context.view_layer.objects.active = o
        bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
base.shape_key_add(name="Basis")
key = base.shape_key_add(name="bend")
for i, v in enumerate(target.data.vertices):
    key.data[i].co = v.co
bpy.data.objects.remove(target)
mesh = base.data
uv = mesh.uv_layers.new(name="UVMap")
for poly in mesh.polygons:
    poly.use_smooth = smooth
    # Each face's angles are taken on the branch of its centre, so the faces on either side
    # of the wrap give the vertices there u = 0 and u = 1: a UV seam.
    centre = math.atan2(poly.center.y, poly.center.x)
    for li in poly.loop_indices:
        co = mesh.vertices[mesh.loops[li].vertex_index].co
        angle = math.atan2(co.y, co.x)
        if angle - centre > math.pi:
            angle -= 2 * math.pi
        elif centre - angle > math.pi:
            angle += 2 * math.pi
        uv.data[li].uv = ((angle + math.pi) / (2 * math.pi), co.z)
mesh.materials.append(bpy.data.materials.new("skin"))
base.select_set(True)
bpy.context.view_layer.objects.active = base
if mode == "artist":
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.smart_project(angle_limit=math.radians(66), island_margin=0.02)
    bpy.ops.object.mode_set(mode="OBJECT")
    image = bpy.data.images.new("checker", width=64, height=64)
    image.generated_type = "COLOR_GRID"
    image.pack()
    cloth = bpy.data.materials.new("cloth")
    cloth.use_nodes = True
    tex = cloth.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = image
    bsdf = cloth.node_tree.nodes["Principled BSDF"]
    cloth.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    mesh.materials.append(cloth)
    # The faces on one side of the mesh's middle (along its longest axis) wear the cloth.
    axis = max(range(3), key=lambda a: max(v.co[a] for v in mesh.vertices) - min(v.co[a] for v in mesh.vertices))
    middle = sum(v.co[axis] for v in mesh.vertices) / len(mesh.vertices)
    for poly in mesh.polygons:
        poly.material_index = 1 if poly.center[axis] > middle else 0
bpy.ops.export_scene.gltf(
    filepath=out, export_format="GLB", export_morph=True, use_selection=True, export_yup=False
)
