"""Physical shape keys (Ma et al. 2012): the shape-key sliders drive a physical blend.

The mesh's first shape key is the base and every other key (but the result key) a target. The
physical result is written into the shape key `morphkit_physical` (value 1) while the target
keys are muted, so the viewport shows it; the linear mode unmutes them again. The solver is
built once per mesh and set of keys, then every slider change is one cheap solve. Pulls are
objects (Empties) with a custom property `morphkit_vertex` (a vertex id), parented to the mesh
or naming it in `morphkit_pull_target`: the vertex is held at the Empty's position (Fig. 5).
Obstacles are closed mesh objects with a custom property `morphkit_obstacle` (true): the blend
collides with them (Fig. 2; the solver is rebuilt when an obstacle moves, and with obstacles
also when a pull moves, since the scene blend holds its pulls).

Live mode answers a slider at once: it shows the blend's predictor (the rotation-aware
interpolation every solve starts from, exact at each key; milliseconds) and solves the
equilibrium on a background thread, which replaces the preview when it is ready, unless the
sliders moved on meanwhile (then the newest values are solved next). The result is the same
equilibrium the "Physical" button gives; only when it is shown depends on time.
"""

import threading
import time

import bpy
import numpy as np

from . import geometry, jumps

RESULT_KEY = "morphkit_physical"
_solvers = {}  # object name -> (signature, PhysicalBlend, F, Predictor)
_last = {}  # object name -> weights and pulls last solved or asked for
_busy = [False]
_jobs = {}  # object name -> _Job solving on a background thread
_wanted = {}  # object name -> (state, blend, weights, pulls) newest live request
POLL_SECONDS = 0.05


def morphkit_module():
    import morphkit

    return morphkit


def target_keys(obj):
    keys = obj.data.shape_keys.key_blocks
    return [k for k in keys[1:] if k.name != RESULT_KEY]


def obstacles_of(scene, obj):
    """Obstacle objects of the scene (closed meshes with `morphkit_obstacle` set)."""
    return [
        o for o in scene.objects
        if o.type == "MESH" and o != obj and bool(o.get("morphkit_obstacle", False))
    ]


def _obstacle_mesh(o, obj):
    """`o`'s (V, F) in `obj`'s object space."""
    F, _ = geometry.triangles(o.data)
    V = geometry.vertices(o.data)
    m = np.array(obj.matrix_world.inverted() @ o.matrix_world)
    return V @ m[:3, :3].T + m[:3, 3], F


def _obstacle(o, obj):
    """`o` as a morphkit Obstacle in `obj`'s object space."""
    import morphkit

    V, F = _obstacle_mesh(o, obj)
    return morphkit.Obstacle.mesh(V, F, name=o.name)


def _volume(obj):
    """The `interior` and `anchor` arguments of the object's blend (None: not asked for)."""
    interior = getattr(obj, "morphkit_interior", "none")
    anchor = "auto" if getattr(obj, "morphkit_anchor", False) else None
    return (None if interior == "none" else interior), anchor


def _signature(obj, scene=None):
    keys = obj.data.shape_keys.key_blocks
    digest = [len(obj.data.vertices), len(obj.data.polygons), keys[0].name, _volume(obj)]
    if scene is not None:
        obstacles = obstacles_of(scene, obj)
        for o in obstacles:
            digest.append((o.name, tuple(np.array(o.matrix_world).ravel()), len(o.data.vertices)))
        digest.append(tuple(np.array(obj.matrix_world).ravel()))
        if obstacles:  # a scene blend holds its pulls: a moved pull rebuilds it
            digest.append(tuple(sorted(pulls_of(obj, scene).items())))
    for k in target_keys(obj):
        c = geometry.key_coords(k)
        digest.append((k.name, float(c.sum()), float(np.abs(c).sum())))
    return tuple(digest)


def solver_for(obj, scene=None):
    """The cached PhysicalBlend of `obj` (a SceneBlend when `scene` has obstacles), rebuilt when
    its keys, topology or obstacles changed."""
    import morphkit

    sig = _signature(obj, scene)
    cached = _solvers.get(obj.name)
    if cached is not None and cached[0] == sig:
        return cached[1], cached[2]
    keys = obj.data.shape_keys.key_blocks
    F, _ = geometry.triangles(obj.data)
    base = geometry.key_coords(keys[0])
    targets = [geometry.key_coords(k) for k in target_keys(obj)]
    obstacles = [_obstacle(o, obj) for o in obstacles_of(scene, obj)] if scene else []
    interior, anchor = _volume(obj)
    if obstacles:
        pulls = [(v, [(0.0, p)]) for v, p in sorted(pulls_of(obj, scene).items())]
        blend = morphkit.SceneBlend(
            base, targets, F, obstacles=obstacles, pulls=pulls, interior=interior, anchor=anchor
        )
    else:
        blend = morphkit.PhysicalBlend(base, targets, F, interior=interior, anchor=anchor)
    # The predictor is taken now: it must not touch the blend while a job solves with it.
    # With an interior or an anchor the add-on takes none, and live mode solves synchronously
    # (the module's predictor would preview the volumetric start; the sync solve is exact).
    predictor = blend.predictor() if interior is None and anchor is None else None
    _solvers[obj.name] = (sig, blend, F, predictor)
    return blend, F


def pulls_of(obj, scene):
    """Pull targets {vertex: object-space position} from the scene's pull objects."""
    inv = obj.matrix_world.inverted()
    out = {}
    for e in scene.objects:
        if "morphkit_vertex" not in e:
            continue
        if e.parent != obj and e.get("morphkit_pull_target") != obj.name:
            continue
        p = inv @ e.matrix_world.translation
        out[int(e["morphkit_vertex"])] = (p.x, p.y, p.z)
    return out


def weights_of(obj):
    return [k.value for k in target_keys(obj)]


def _solve(blend, w, pulls):
    """One equilibrium with morphkit only (no bpy: safe on any thread); (X, stats, contacts)."""
    if isinstance(blend, morphkit_module().SceneBlend):
        X = blend.solve(w)  # its pulls were given when it was built (see solver_for)
        stats = blend.last_stats
        return X, stats["solver"], stats["collision"]["contacts"]
    X = blend.solve(w, pulls=pulls or None)
    return X, blend.last_stats, None


def _show(obj, X, what):
    """Shows `X` in the result key (targets muted); `what` is "physical" or "preview"."""
    key = geometry.ensure_key(obj, RESULT_KEY)
    geometry.set_key_coords(key, X)
    key.value = 1.0
    key.mute = False
    for k in target_keys(obj):
        k.mute = True
    obj.data.update()
    obj["morphkit_showing"] = what


def _show_solved(obj, out):
    X, stats, contacts = out
    _show(obj, X, "physical")
    if contacts is not None:
        obj["morphkit_contacts"] = contacts
    obj["morphkit_last_stats"] = {
        k: v for k, v in stats.items() if isinstance(v, (int, float, bool))
    }


def _state(obj, scene):
    w = weights_of(obj)
    pulls = pulls_of(obj, scene)
    return (tuple(w), tuple(sorted(pulls.items()))), w, pulls


def solve_into_key(obj, scene):
    """Solves for the current sliders and pulls and shows the result; returns seconds."""
    _settle(obj.name)
    t0 = time.perf_counter()
    blend, _ = solver_for(obj, scene)
    state, w, pulls = _state(obj, scene)
    _show_solved(obj, _solve(blend, w, pulls))
    _last[obj.name] = state
    return time.perf_counter() - t0


class _Job(threading.Thread):
    """One live solve on a background thread (the solve releases the GIL)."""

    def __init__(self, name, state, blend, w, pulls):
        super().__init__(daemon=True, name=f"morphkit live {name}")
        self.state, self.blend, self.w, self.pulls = state, blend, w, pulls
        self.out = self.error = None
        self.started_at = time.perf_counter()
        self.seconds = 0.0
        self.start()

    def run(self):
        try:
            self.out = _solve(self.blend, self.w, self.pulls)
        except Exception as e:  # reported on the main thread
            self.error = e
        self.seconds = time.perf_counter() - self.started_at


def _request(obj, scene):
    """Live update of `obj`: the preview now, the equilibrium from a background job."""
    blend, _ = solver_for(obj, scene)
    state, w, pulls = _state(obj, scene)
    _last[obj.name] = state
    if not obj.morphkit_live_preview or _solvers[obj.name][3] is None:
        obj["morphkit_latency_ms"] = 1e3 * solve_into_key(obj, scene)
        return
    t0 = time.perf_counter()
    _show(obj, _solvers[obj.name][3].predict(w), "preview")  # cached by solver_for above
    obj["morphkit_preview_ms"] = 1e3 * (time.perf_counter() - t0)
    _wanted[obj.name] = (state, blend, w, pulls)
    if obj.name not in _jobs:
        _jobs[obj.name] = _Job(obj.name, state, blend, w, pulls)
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=POLL_SECONDS)


def _poll():
    """Timer: shows finished jobs that are still wanted and starts the newest request."""
    for name, job in list(_jobs.items()):
        if job.is_alive():
            continue
        del _jobs[name]
        obj = bpy.data.objects.get(name)
        wanted = _wanted.get(name)
        if obj is None or wanted is None or not getattr(obj, "morphkit_live", False):
            continue
        if job.error is not None:
            _wanted.pop(name)
            print(f"morphkit: {name}: {job.error}")
        elif job.state == wanted[0] and job.blend is wanted[1]:
            _wanted.pop(name)
            _show_solved(obj, job.out)
            obj["morphkit_latency_ms"] = 1e3 * job.seconds
        else:  # the sliders moved on while this job solved: solve the newest values
            _jobs[name] = _Job(name, *wanted)
    return POLL_SECONDS if _jobs else None


def _settle(name):
    """Waits for `name`'s live job (the blend serves one solve at a time) and drops it."""
    job = _jobs.pop(name, None)
    if job is not None:
        job.join()
    _wanted.pop(name, None)


def finish_live(timeout=300.0):
    """Waits for the live jobs and shows their results (for scripts and `blender -b`, where
    timers do not run). Returns whether everything finished within `timeout` seconds."""
    deadline = time.perf_counter() + timeout
    while _jobs:
        for job in list(_jobs.values()):
            job.join(max(0.0, deadline - time.perf_counter()))
        if any(j.is_alive() for j in _jobs.values()):
            return False
        _poll()
    return True


def show_linear(obj):
    if obj.data.shape_keys is None:
        return
    for k in target_keys(obj):
        k.mute = False
    key = obj.data.shape_keys.key_blocks.get(RESULT_KEY)
    if key is not None:
        key.value = 0.0
        key.mute = True
    obj.data.update()


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


def _live_handler(scene, depsgraph=None):
    """Re-solves live objects whose sliders or pulls changed (the slider drives the blend)."""
    if _busy[0]:
        return
    _busy[0] = True
    try:
        for obj in scene.objects:
            if obj.type != "MESH" or not getattr(obj, "morphkit_live", False):
                continue
            if obj.data.shape_keys is None:
                continue
            state, _, _ = _state(obj, scene)
            if _last.get(obj.name) != state:
                try:
                    _request(obj, scene)
                except Exception as e:  # a handler must never raise into Blender
                    print(f"morphkit: {obj.name}: {e}")
    finally:
        _busy[0] = False


def _live_changed(self, context):
    if self.morphkit_live:
        _last.pop(self.name, None)
        _live_handler(context.scene)
    else:
        show_linear(self)


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
        row = layout.row(align=True)
        row.prop(obj, "morphkit_interior", text="Interior")
        row.prop(obj, "morphkit_anchor")
        if obj.data.shape_keys is not None:
            col = layout.column(align=True)
            for k in target_keys(obj):
                col.prop(k, "value", text=k.name, slider=True)
        row = layout.row(align=True)
        row.operator(MORPHKIT_OT_physical_update.bl_idname, text="Physical")
        row.operator(MORPHKIT_OT_physical_linear.bl_idname, text="Linear")
        layout.operator(MORPHKIT_OT_physical_bake.bl_idname)
        layout.operator(MORPHKIT_OT_export_scene.bl_idname)
        if obj.name in _jobs:
            layout.label(text="solving… (showing the preview)")
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
    del bpy.types.Object.morphkit_interior
    del bpy.types.Object.morphkit_anchor
    _solvers.clear()
    _last.clear()
    _wanted.clear()
