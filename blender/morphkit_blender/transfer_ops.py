"""Deformation transfer and rig transfer between Blender objects.

Markers are vertex pairs `[source, target]` kept in a text block (default
`morphkit_markers.json`, the `{"pairs": [[s, t], ...]}` file the CLI reads; save it with the
text editor to replay a run in a pipeline). The source animation is the source object as
Blender evaluates it over the scene's frame range (shape keys, a Mesh Cache, any modifier that
keeps the vertex count); the result is one shape key per frame on the target, keyed to show at
its frame. A rig transfer moves every shape key of the source onto the target as a shape key of
the same name.

Three options of the panel are the CLI's flags: *Refine correspondence* (`transfer --refine`,
closest-point refinement after the marker warp) and *Local stretch* (`transfer --local-stretch
--area-weighted`, with the fold guard), for the animation transfer, which together are the
configuration the README measures best on horse -> camel and cat -> dog; and *Refine rig
correspondence* (`rig --refine`) for the rig transfer, whose correspondence `morphkit rig` does
not refine by default (the refinement moved ICT's cheekPuff_L by 6.9 % of its motion onto a
copy of the head). Each defaults to the library's default (`morphkit.transfer_defaults()` and
`morphkit.rig_defaults()`, issue 55), so a new scene transfers as `morphkit transfer` and
`morphkit rig` and the module do without options.
"""

import json

import bpy

from . import geometry

FRAME_PREFIX = "morphkit_frame_"


def _markers_text(scene):
    name = scene.morphkit_markers or "morphkit_markers.json"
    text = bpy.data.texts.get(name)
    if text is None:
        text = bpy.data.texts.new(name)
        text.from_string(json.dumps({"pairs": []}))
    return text


def read_markers(scene):
    """The marker pairs of the scene's markers text block."""
    data = json.loads(_markers_text(scene).as_string() or "{}")
    pairs = data.get("pairs", data) if isinstance(data, dict) else data
    return [[int(s), int(t)] for s, t in pairs]


def write_markers(scene, pairs):
    _markers_text(scene).from_string(json.dumps({"pairs": pairs}))


def _meshes(scene):
    src, tgt = scene.morphkit_source, scene.morphkit_target
    if src is None or tgt is None or src.type != "MESH" or tgt.type != "MESH":
        raise ValueError("choose a source and a target mesh object")
    return src, tgt


def _reference(obj):
    """Reference shape: the Basis key when there are shape keys, else the mesh."""
    keys = obj.data.shape_keys
    if keys is not None:
        return geometry.key_coords(keys.key_blocks[0])
    return geometry.vertices(obj.data)


def correspondence(scene, src, tgt, refine):
    import morphkit

    FS, _ = geometry.triangles(src.data)
    FT, _ = geometry.triangles(tgt.data)
    VS, VT = _reference(src), _reference(tgt)
    corr = morphkit.Correspondence.from_markers(VS, FS, VT, FT, read_markers(scene), refine=refine)
    return VS, FS, VT, FT, corr


class MORPHKIT_OT_add_marker(bpy.types.Operator):
    """Add a marker pair: the given vertex ids, or the active (last selected) vertex of the
    source and of the target"""

    bl_idname = "morphkit.add_marker"
    bl_label = "Add marker pair"
    bl_options = {"REGISTER", "UNDO"}

    source_vertex: bpy.props.IntProperty(default=-1)
    target_vertex: bpy.props.IntProperty(default=-1)

    def execute(self, context):
        try:
            src, tgt = _meshes(context.scene)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}

        def selected(obj):
            ids = [v.index for v in obj.data.vertices if v.select]
            return ids[-1] if ids else -1

        s = self.source_vertex if self.source_vertex >= 0 else selected(src)
        t = self.target_vertex if self.target_vertex >= 0 else selected(tgt)
        if s < 0 or t < 0 or s >= len(src.data.vertices) or t >= len(tgt.data.vertices):
            self.report({"ERROR"}, "select one vertex on the source and one on the target")
            return {"CANCELLED"}
        pairs = read_markers(context.scene)
        pairs.append([s, t])
        write_markers(context.scene, pairs)
        self.report({"INFO"}, f"{len(pairs)} marker pairs")
        return {"FINISHED"}


def _frame_keys(obj, frames, first_frame):
    """One shape key per frame on `obj`, keyed 1 at its frame and 0 at the neighbours."""
    geometry.ensure_key(obj, "Basis")
    for old in [k for k in obj.data.shape_keys.key_blocks if k.name.startswith(FRAME_PREFIX)]:
        obj.shape_key_remove(old)
    for i, X in enumerate(frames):
        f = first_frame + i
        key = obj.shape_key_add(name=f"{FRAME_PREFIX}{f:04d}", from_mix=False)
        geometry.set_key_coords(key, X)
        for g, v in ((f - 1, 0.0), (f, 1.0), (f + 1, 0.0)):
            key.value = v
            key.keyframe_insert("value", frame=g)
        key.value = 0.0


class MORPHKIT_OT_transfer(bpy.types.Operator):
    """Transfer the source's animation over the frame range onto the target (shape keys)"""

    bl_idname = "morphkit.transfer"
    bl_label = "Transfer animation"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        import morphkit

        scene = context.scene
        try:
            src, tgt = _meshes(scene)
            VS, FS, VT, FT, corr = correspondence(scene, src, tgt, scene.morphkit_refine)
            stretch = scene.morphkit_local_stretch
            tr = morphkit.Transfer(VS, FS, VT, FT, corr, local_stretch=stretch, area_weighted=stretch)
            frames = []
            current = scene.frame_current
            for f in range(scene.frame_start, scene.frame_end + 1):
                scene.frame_set(f)
                frames.append(geometry.evaluated_vertices(src, context.evaluated_depsgraph_get()))
            scene.frame_set(current)
            out = tr.transfer_many(frames)
        except (ValueError, morphkit.MorphkitError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        _frame_keys(tgt, out, scene.frame_start)
        self.report({"INFO"}, f"transferred {len(out)} frames")
        return {"FINISHED"}


class MORPHKIT_OT_transfer_rig(bpy.types.Operator):
    """Move every shape key of the source onto the target as a shape key of the same name
    (the target's neutral stays where it is)"""

    bl_idname = "morphkit.transfer_rig"
    bl_label = "Transfer shape-key rig"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        import morphkit

        scene = context.scene
        try:
            src, tgt = _meshes(scene)
            if src.data.shape_keys is None or len(src.data.shape_keys.key_blocks) < 2:
                raise ValueError("the source has no shape keys to transfer")
            VS, FS, VT, FT, corr = correspondence(scene, src, tgt, scene.morphkit_rig_refine)
            tr = morphkit.RigTransfer(VS, FS, VT, FT, corr)
            keys = list(src.data.shape_keys.key_blocks[1:])
            out = tr.transfer_many([geometry.key_coords(k) for k in keys])
        except (ValueError, morphkit.MorphkitError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        geometry.ensure_key(tgt, "Basis")
        for k, X in zip(keys, out):
            key = tgt.data.shape_keys.key_blocks.get(k.name) or tgt.shape_key_add(
                name=k.name, from_mix=False
            )
            geometry.set_key_coords(key, X)
        self.report({"INFO"}, f"transferred {len(keys)} shape keys")
        return {"FINISHED"}


class MORPHKIT_PT_transfer(bpy.types.Panel):
    bl_label = "Transfer"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "morphkit"

    def draw(self, context):
        layout, scene = self.layout, context.scene
        layout.prop(scene, "morphkit_source")
        layout.prop(scene, "morphkit_target")
        layout.prop(scene, "morphkit_markers")
        layout.prop(scene, "morphkit_refine")
        layout.prop(scene, "morphkit_local_stretch")
        layout.prop(scene, "morphkit_rig_refine")
        layout.operator(MORPHKIT_OT_add_marker.bl_idname)
        layout.operator(MORPHKIT_OT_transfer.bl_idname)
        layout.operator(MORPHKIT_OT_transfer_rig.bl_idname)


classes = (MORPHKIT_OT_add_marker, MORPHKIT_OT_transfer, MORPHKIT_OT_transfer_rig, MORPHKIT_PT_transfer)


def _library_defaults(which):
    """The library's defaults (`morphkit.transfer_defaults()` or `morphkit.rig_defaults()`),
    or an empty dict when the module is not found (the operators cannot run then anyway)."""
    try:
        import morphkit

        return getattr(morphkit, which)()
    except (ImportError, AttributeError):
        return {}


def register():
    defaults = _library_defaults("transfer_defaults")
    rig = _library_defaults("rig_defaults")
    bpy.types.Scene.morphkit_source = bpy.props.PointerProperty(name="Source", type=bpy.types.Object)
    bpy.types.Scene.morphkit_target = bpy.props.PointerProperty(name="Target", type=bpy.types.Object)
    bpy.types.Scene.morphkit_markers = bpy.props.StringProperty(
        name="Markers text", default="morphkit_markers.json"
    )
    bpy.types.Scene.morphkit_refine = bpy.props.BoolProperty(
        name="Refine correspondence",
        description=(
            "Refine the marker correspondence of the animation transfer by closest points "
            "(morphkit transfer --refine)"
        ),
        default=bool(defaults.get("refine", False)),
    )
    bpy.types.Scene.morphkit_rig_refine = bpy.props.BoolProperty(
        name="Refine rig correspondence",
        description=(
            "Refine the marker correspondence of the shape-key rig transfer by closest points "
            "(morphkit rig --refine; off by default, as there)"
        ),
        default=bool(rig.get("refine", False)),
    )
    bpy.types.Scene.morphkit_local_stretch = bpy.props.BoolProperty(
        name="Local stretch",
        description=(
            "Transfer each matched gradient as a stretch in the target triangle's own frame, "
            "area-weighted and guarded against creases (transfer --local-stretch --area-weighted)"
        ),
        default=bool(defaults.get("local_stretch", False) and defaults.get("area_weighted", False)),
    )
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
    del bpy.types.Scene.morphkit_source
    del bpy.types.Scene.morphkit_target
    del bpy.types.Scene.morphkit_markers
    del bpy.types.Scene.morphkit_refine
    del bpy.types.Scene.morphkit_rig_refine
    del bpy.types.Scene.morphkit_local_stretch
