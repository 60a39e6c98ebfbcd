"""Synthesis tools (Wang & Lee 2008 Sec. 3.2): flexibility as a colour attribute, scribbles as
face selections refined into partitions (Fig. 8), the scribble saved as the JSON the CLI's
recipes read, and a recipe's result as shape keys on its target.

Flexibility is measured over the active object's shape keys (each non-basis key one frame).
"""

import json

import bpy
import numpy as np

from . import geometry, transfer_ops

FLEX_ATTR = "morphkit_flexibility"
PART_ATTR = "morphkit_partitions"


def _frames_of_keys(obj):
    keys = obj.data.shape_keys
    if keys is None or len(keys.key_blocks) < 2:
        raise ValueError("the object needs shape keys (its frames) to measure flexibility")
    base = geometry.key_coords(keys.key_blocks[0])
    frames = [
        geometry.key_coords(k)
        for k in keys.key_blocks[1:]
        if not k.name.startswith("morphkit_")
    ]
    return base, frames


def flexibility_of(obj):
    import morphkit

    base, frames = _frames_of_keys(obj)
    F, P = geometry.triangles(obj.data)
    return base, F, P, morphkit.flexibility(base, F, frames)


class MORPHKIT_OT_flexibility(bpy.types.Operator):
    """Measure flexibility over the shape keys and show it as a face colour attribute"""

    bl_idname = "morphkit.flexibility"
    bl_label = "Show flexibility"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        import morphkit

        obj = context.active_object
        try:
            _, _, P, flex = flexibility_of(obj)
        except (ValueError, morphkit.MorphkitError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        geometry.face_colors(obj.data, FLEX_ATTR, flex, P, geometry.viridis_like)
        obj["morphkit_flex_max"] = float(flex.max())
        return {"FINISHED"}


class MORPHKIT_OT_refine_scribble(bpy.types.Operator):
    """Refine the selected faces (the scribble) by the flexibility partitions: whole stiff
    partitions become selected (intelligent scribbling), saved as a scribble text block"""

    bl_idname = "morphkit.refine_scribble"
    bl_label = "Refine scribble"
    bl_options = {"REGISTER", "UNDO"}

    text_name: bpy.props.StringProperty(default="morphkit_scribble.json")

    def execute(self, context):
        import morphkit

        obj = context.active_object
        was_edit = obj.mode == "EDIT"
        if was_edit:
            bpy.ops.object.mode_set(mode="OBJECT")
        try:
            base, F, P, flex = flexibility_of(obj)
            selected_polys = np.array([p.select for p in obj.data.polygons])
            scribbled = np.flatnonzero(selected_polys[P]).tolist()
            if not scribbled:
                raise ValueError("select the faces to scribble first")
            parts = morphkit.Partitions(base, F, flex)
            sel = parts.refine(triangles=scribbled)
        except (ValueError, morphkit.MorphkitError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        poly_sel = np.zeros(len(obj.data.polygons), dtype=bool)
        poly_sel[P[sel]] = True
        obj.data.polygons.foreach_set("select", poly_sel)
        labels = parts.labels.astype(float)
        colors = np.where(sel, 1.0, 0.15 + 0.5 * (labels % 7) / 7.0 * parts.stiff)
        geometry.face_colors(obj.data, PART_ATTR, colors, P, geometry.viridis_like)
        text = bpy.data.texts.get(self.text_name) or bpy.data.texts.new(self.text_name)
        text.from_string(json.dumps({"triangles": np.flatnonzero(sel).tolist()}))
        obj["morphkit_selected_triangles"] = int(sel.sum())
        if was_edit:
            bpy.ops.object.mode_set(mode="EDIT")
        return {"FINISHED"}


class MORPHKIT_OT_rotate_partition(bpy.types.Operator):
    """Pose modification (Sec. 3.2.4): turn the scribbled (selected) partitions about `axis`
    by `angle`; the joints blend and the other stiff parts stay. The edited pose goes into the
    shape key `morphkit_pose`"""

    bl_idname = "morphkit.rotate_partition"
    bl_label = "Rotate selected partition"
    bl_options = {"REGISTER", "UNDO"}

    axis: bpy.props.FloatVectorProperty(name="Axis", size=3, default=(0.0, 0.0, 1.0))
    angle: bpy.props.FloatProperty(name="Angle", subtype="ANGLE", default=0.5)

    def execute(self, context):
        import morphkit

        obj = context.active_object
        was_edit = obj.mode == "EDIT"
        if was_edit:
            bpy.ops.object.mode_set(mode="OBJECT")
        try:
            base, F, P, flex = flexibility_of(obj)
            selected_polys = np.array([p.select for p in obj.data.polygons])
            mask = selected_polys[P]
            if not mask.any():
                raise ValueError("select the faces of the part to turn first")
            parts = morphkit.Partitions(base, F, flex)
            X = parts.edit_pose(mask, tuple(self.axis), self.angle)
        except (ValueError, morphkit.MorphkitError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        key = geometry.ensure_key(obj, "morphkit_pose")
        geometry.set_key_coords(key, X)
        key.value = 1.0
        obj.data.update()
        if was_edit:
            bpy.ops.object.mode_set(mode="EDIT")
        return {"FINISHED"}


class MORPHKIT_OT_synthesize(bpy.types.Operator):
    """Run a synthesis recipe (the TOML file of `morphkit synth`) and put its frames on the
    active object as keyed shape keys"""

    bl_idname = "morphkit.synthesize"
    bl_label = "Synthesize from recipe"
    bl_options = {"REGISTER", "UNDO"}

    recipe: bpy.props.StringProperty(name="Recipe", subtype="FILE_PATH")

    def execute(self, context):
        import morphkit

        obj = context.active_object
        try:
            frames, F = morphkit.synthesize(bpy.path.abspath(self.recipe))
            if frames.shape[1] != len(obj.data.vertices):
                raise ValueError(
                    f"the recipe's target has {frames.shape[1]} vertices, "
                    f"{obj.name} has {len(obj.data.vertices)}"
                )
        except (ValueError, morphkit.MorphkitError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        transfer_ops._frame_keys(obj, frames, context.scene.frame_start)
        return {"FINISHED"}


class MORPHKIT_PT_synth(bpy.types.Panel):
    bl_label = "Synthesis"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "morphkit"

    def draw(self, context):
        layout = self.layout
        layout.operator(MORPHKIT_OT_flexibility.bl_idname)
        layout.operator(MORPHKIT_OT_refine_scribble.bl_idname)
        layout.operator(MORPHKIT_OT_rotate_partition.bl_idname)
        layout.operator(MORPHKIT_OT_synthesize.bl_idname)


classes = (
    MORPHKIT_OT_flexibility,
    MORPHKIT_OT_refine_scribble,
    MORPHKIT_OT_rotate_partition,
    MORPHKIT_OT_synthesize,
    MORPHKIT_PT_synth,
)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
