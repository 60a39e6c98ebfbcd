"""The physical shape keys' operators, panel and properties (the Sidebar's "Physical shape
keys"); what they run is in `physical` (the blend, live mode)."""

import bpy

from . import geometry, jumps
from .physical import (
    BAKE_PROP,
    _jobs,
    _last,
    _live_changed,
    _live_handler,
    _obstacle_mesh,
    _poll,
    _settle,
    _settling,
    _solvers,
    _volume,
    _wanted,
    finish_live,
    obstacles_of,
    pulls_of,
    show_linear,
    solve_into_key,
    solver_for,
    target_keys,
    weights_of,
)


def _has_keys(context):
    obj = context.active_object
    return (
        obj is not None
        and obj.type == "MESH"
        and obj.data.shape_keys is not None
        and len(target_keys(obj)) >= 1
    )


class MORPHKIT_OT_physical_update(bpy.types.Operator):
    """Solve the physical blend for the current shape-key values and pulls"""

    bl_idname = "morphkit.physical_update"
    bl_label = "Update physical blend"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _has_keys(context)

    def execute(self, context):
        import morphkit

        obj = context.active_object
        try:
            s = solve_into_key(obj, context.scene)
        except morphkit.MorphkitError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        obj["morphkit_latency_ms"] = 1e3 * s
        self.report({"INFO"}, f"physical blend in {1e3 * s:.0f} ms")
        return {"FINISHED"}


class MORPHKIT_OT_physical_linear(bpy.types.Operator):
    """Show the linear blend of the shape keys again"""

    bl_idname = "morphkit.physical_linear"
    bl_label = "Show linear blend"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _has_keys(context)

    def execute(self, context):
        context.active_object.morphkit_live = False
        show_linear(context.active_object)
        return {"FINISHED"}


class MORPHKIT_OT_physical_bake(bpy.types.Operator):
    """Bake the shape-key animation over the scene's frame range as a physical PC2 cache on a
    Mesh Cache modifier"""

    bl_idname = "morphkit.physical_bake"
    bl_label = "Bake physical animation (PC2)"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(name="PC2 file", subtype="FILE_PATH", default="")
    threads: bpy.props.IntProperty(name="Threads", default=2, min=1, max=64)

    @classmethod
    def poll(cls, context):
        return _has_keys(context)

    def execute(self, context):
        import morphkit

        obj, scene = context.active_object, context.scene
        path = bpy.path.abspath(self.filepath or f"//{bpy.path.clean_name(obj.name)}_physical.pc2")
        if path.startswith("//"):
            self.report({"ERROR"}, "save the .blend file first or give an absolute PC2 path")
            return {"CANCELLED"}
        show_linear(obj)
        rows = []
        current = scene.frame_current
        for f in range(scene.frame_start, scene.frame_end + 1):
            scene.frame_set(f)
            rows.append(weights_of(obj))
        scene.frame_set(current)
        _settle(obj.name)
        try:
            blend, F = solver_for(obj, scene)
            # Obstacles and pulls are taken at their current pose (frame number 0 of the
            # scene blend) for every frame; frames are independent, so threads change nothing.
            frames = blend.solve_many(rows, threads=self.threads)
            morphkit.write_animation(path, frames, F)
            # A part that snaps between two equilibria of the springs is shown, not hidden.
            keys = obj.data.shape_keys.key_blocks
            base = geometry.key_coords(keys[0])
            targets = [geometry.key_coords(k) for k in target_keys(obj)]
            continuity = morphkit.continuity(frames, jumps.linear_frames(base, targets, rows))
        except morphkit.MorphkitError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        mod = obj.modifiers.get("morphkit physical") or obj.modifiers.new(
            "morphkit physical", "MESH_CACHE"
        )
        mod.cache_format = "PC2"
        mod.filepath = path
        mod.frame_start = scene.frame_start
        mod.frame_scale = 1.0
        obj["morphkit_baked_frames"] = len(rows)
        jumps.mark(obj, continuity)
        if continuity["jumps"]:
            j = max(continuity["jumps"], key=lambda j: j["ratio"])
            a, b = (scene.frame_start + k for k in j["frames"])
            self.report(
                {"WARNING"},
                f"baked {len(rows)} frames to {path}; a part jumped between frames {a} and {b} "
                f"({len(j['vertices'])} vertices, {j['ratio']:.1f}x the linear blend's step): "
                f"vertex group '{jumps.JUMPS_GROUP}'",
            )
            return {"FINISHED"}
        self.report({"INFO"}, f"baked {len(rows)} frames to {path}")
        return {"FINISHED"}


class MORPHKIT_OT_export_scene(bpy.types.Operator):
    """Write the blend as the scene file `morphkit blend --scene` reads: base, target and
    obstacle meshes as OBJ, the animated slider values over the frame range as a weights file,
    the pulls, and scene.toml, so that a pipeline can replay it"""

    bl_idname = "morphkit.export_scene"
    bl_label = "Export scene (TOML)"

    directory: bpy.props.StringProperty(name="Folder", subtype="DIR_PATH")

    @classmethod
    def poll(cls, context):
        return _has_keys(context)

    def execute(self, context):
        import json
        import os

        import morphkit

        obj, scene = context.active_object, context.scene
        out = bpy.path.abspath(self.directory)
        if not out or out.startswith("//"):
            self.report({"ERROR"}, "give an absolute folder")
            return {"CANCELLED"}
        os.makedirs(out, exist_ok=True)
        keys = obj.data.shape_keys.key_blocks
        F, _ = geometry.triangles(obj.data)
        clean = bpy.path.clean_name
        morphkit.write(os.path.join(out, "base.obj"), geometry.key_coords(keys[0]), F)
        targets = []
        for k in target_keys(obj):
            name = f"target_{clean(k.name)}.obj"
            morphkit.write(os.path.join(out, name), geometry.key_coords(k), F)
            targets.append(name)
        rows, current = [], scene.frame_current
        for f in range(scene.frame_start, scene.frame_end + 1):
            scene.frame_set(f)
            rows.append(weights_of(obj))
        scene.frame_set(current)
        with open(os.path.join(out, "weights.json"), "w") as fh:
            json.dump({"frames": rows}, fh)
        lines = [
            'base = "base.obj"',
            "targets = [" + ", ".join(json.dumps(t) for t in targets) + "]",
            "",
            "[weights]",
            'file = "weights.json"',
            "",
            "[output]",
            f"fps = {scene.render.fps / scene.render.fps_base}",
        ]
        interior, anchor = _volume(obj)
        if interior or anchor:
            lines += ["", "[blend]"]
            lines += [f"interior = {json.dumps(interior)}"] if interior else []
            lines += [f"anchor = {json.dumps(anchor)}"] if anchor else []
        for o in obstacles_of(scene, obj):
            ob = _obstacle_mesh(o, obj)
            name = f"obstacle_{clean(o.name)}.obj"
            morphkit.write(os.path.join(out, name), *ob)
            lines += ["", "[[obstacle]]", f"name = {json.dumps(o.name)}", f'mesh = "{name}"']
        for v, p in sorted(pulls_of(obj, scene).items()):
            lines += ["", "[[pull]]", f"vertex = {v}", f"position = [{p[0]!r}, {p[1]!r}, {p[2]!r}]"]
        with open(os.path.join(out, "scene.toml"), "w") as fh:
            fh.write("\n".join(lines) + "\n")
        self.report({"INFO"}, f"wrote {os.path.join(out, 'scene.toml')}")
        return {"FINISHED"}


class MORPHKIT_PT_physical(bpy.types.Panel):
    bl_label = "Physical shape keys"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "morphkit"

    def draw(self, context):
        layout = self.layout
        obj = context.active_object
        if obj is None or obj.type != "MESH":
            layout.label(text="Select a mesh with shape keys")
            return
        layout.prop(obj, "morphkit_live")
        if obj.morphkit_live:
            layout.prop(obj, "morphkit_live_preview")
            if obj.morphkit_live_preview:
                layout.prop(obj, "morphkit_interactive")
        row = layout.row(align=True)
        row.prop(obj, "morphkit_interior", text="Interior")
        row.prop(obj, "morphkit_anchor")
        if obj.data.shape_keys is not None:
            col = layout.column(align=True)
            baked = obj.get(BAKE_PROP)
            if baked is not None:  # the sliders of a baked rig are its properties
                col.label(text="Baked sliders (drivers):")
                for name, prop in zip(baked["sliders"], baked["properties"]):
                    path = f'["{bpy.utils.escape_identifier(prop)}"]'
                    col.prop(obj, path, text=name, slider=True)
            else:
                for k in target_keys(obj):
                    col.prop(k, "value", text=k.name, slider=True)
        row = layout.row(align=True)
        row.operator(MORPHKIT_OT_physical_update.bl_idname, text="Physical")
        row.operator(MORPHKIT_OT_physical_linear.bl_idname, text="Linear")
        layout.operator(MORPHKIT_OT_physical_bake.bl_idname)
        layout.operator(MORPHKIT_OT_export_scene.bl_idname)
        layout.operator("morphkit.bake_correctives")
        if obj.name in _jobs:
            layout.label(text=f"solving… (showing the {obj.get('morphkit_showing', 'preview')})")
        if obj.get("morphkit_showing") == "interactive" and "morphkit_error_estimate" in obj:
            layout.label(text=f"interactive, within {100 * obj['morphkit_error_estimate']:.2f} % of the size")
        if "morphkit_latency_ms" in obj:
            layout.label(text=f"last solve {obj['morphkit_latency_ms']:.0f} ms")


classes = (
    MORPHKIT_OT_physical_update,
    MORPHKIT_OT_physical_linear,
    MORPHKIT_OT_physical_bake,
    MORPHKIT_OT_export_scene,
    MORPHKIT_PT_physical,
)


def register():
    bpy.types.Object.morphkit_live = bpy.props.BoolProperty(
        name="Live physical blend",
        description="Re-solve the physical blend whenever a shape-key value or pull changes",
        default=False,
        update=_live_changed,
    )
    bpy.types.Object.morphkit_live_preview = bpy.props.BoolProperty(
        name="Preview while solving",
        description="Show the predictor at once and solve the equilibrium in the background "
        "(off: every change waits for its solve)",
        default=True,
    )
    bpy.types.Object.morphkit_interactive = bpy.props.BoolProperty(
        name="Interactive while dragging",
        description="While a slider moves, show the rig's interactive shape (tens of "
        "milliseconds, close to the equilibrium; the rig is prepared on first use, about a "
        "minute for ten targets, and kept next to the saved .blend file), and the equilibrium "
        "once the sliders rest. Surface blends without pulls",
        default=False,
    )
    bpy.types.Object.morphkit_interior = bpy.props.EnumProperty(
        name="Interior",
        description="Internal springs that keep the volume (Ma et al. Sec. 3.1); closed parts only",
        items=[
            ("none", "None", "Surface springs only"),
            ("lattice", "Lattice", "A lattice of internal springs inside each closed part"),
        ],
        default="none",
    )
    bpy.types.Object.morphkit_anchor = bpy.props.BoolProperty(
        name="Anchor",
        description="A rigid anchor inside the mesh that the blend follows (Sec. 3.4), instead "
        "of the vertices that stay put",
        default=False,
    )
    for c in classes:
        bpy.utils.register_class(c)
    bpy.app.handlers.depsgraph_update_post.append(_live_handler)
    bpy.app.handlers.frame_change_post.append(_live_handler)


def unregister():
    for h in (bpy.app.handlers.depsgraph_update_post, bpy.app.handlers.frame_change_post):
        if _live_handler in h:
            h.remove(_live_handler)
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
    finish_live()
    del bpy.types.Object.morphkit_live
    del bpy.types.Object.morphkit_live_preview
    del bpy.types.Object.morphkit_interactive
    del bpy.types.Object.morphkit_interior
    del bpy.types.Object.morphkit_anchor
    _solvers.clear()
    _last.clear()
    _wanted.clear()
    _settling.clear()
