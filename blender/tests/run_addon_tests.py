"""Headless checks of the add-on, run inside Blender:

    blender -b --factory-startup --python-exit-code 1 --python blender/tests/run_addon_tests.py \
        -- ADDON.zip DATA_DIR OUT_DIR

Installs and enables the add-on from the zip, builds scenes from real meshes, runs every
operator and compares the results with the morphkit module within 1e-6 of the bounding-box
diagonal (Blender stores float32), renders one Workbench image per mode to OUT_DIR and checks
that it is not blank. Writes OUT_DIR/results.json. Any failed check raises (exit code 1).
"""

import json
import pathlib
import sys
import time

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1 :]
ZIP, DATA, OUT = pathlib.Path(argv[0]), pathlib.Path(argv[1]), pathlib.Path(argv[2])
OUT.mkdir(parents=True, exist_ok=True)
results = {}

bpy.ops.preferences.addon_install(filepath=str(ZIP), overwrite=True)
bpy.ops.preferences.addon_enable(module="morphkit_blender")
import morphkit  # noqa: E402  (found by the add-on: vendored in the zip)
from morphkit_blender import geometry, jumps, physical  # noqa: E402

results["module"] = morphkit.__file__


def check(cond, what):
    if not cond:
        raise AssertionError(what)


def diag(V):
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def new_object(name, V, F, keys=()):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(V.tolist(), [], F.tolist())
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    if keys:
        obj.shape_key_add(name="Basis", from_mix=False)
        for kname, X in keys:
            k = obj.shape_key_add(name=kname, from_mix=False)
            geometry.set_key_coords(k, X)
    return obj


def activate(obj):
    for o in bpy.context.scene.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def render(name, obj, color_attr=None, also=()):
    """A Workbench image framing `obj` (and showing `also`); returns the pixel std."""
    scene = bpy.context.scene
    for o in scene.objects:
        o.hide_render = o.type == "MESH" and o != obj and o not in also
    cam = bpy.data.objects.get("morphkit_cam")
    if cam is None:
        cam = bpy.data.objects.new("morphkit_cam", bpy.data.cameras.new("morphkit_cam"))
        scene.collection.objects.link(cam)
    scene.camera = cam
    bpy.context.view_layer.update()
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    pts = np.array([ev.matrix_world @ v.co for v in ev.data.vertices])
    c = (pts.max(0) + pts.min(0)) / 2
    r = diag(pts)
    cam.location = (c[0] + 0.9 * r, c[1] - 1.3 * r, c[2] + 0.7 * r)
    direction = c - np.array(cam.location)
    from mathutils import Vector

    cam.rotation_euler = Vector(direction).to_track_quat("-Z", "Y").to_euler()
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "STUDIO"
    scene.display.shading.color_type = "VERTEX" if color_attr else "MATERIAL"  # the active colour attribute
    scene.render.resolution_x, scene.render.resolution_y = 480, 360
    scene.render.filepath = str(OUT / f"{name}.png")
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(scene.render.filepath)
    px = np.array(img.pixels[:]).reshape(-1, 4)[:, :3]
    bpy.data.images.remove(img)
    std = float(px.std())
    check(std > 0.02, f"{name}.png is blank (pixel std {std})")
    if color_attr:  # the colour attribute is shown: saturated pixels, not only greys
        sat = float((px.max(axis=1) - px.min(axis=1)).max())
        check(sat > 0.3, f"{name}.png shows no colours (max saturation {sat})")
    return std


# --- Physical shape keys ---------------------------------------------------------------
d = DATA / "cragl-bending-cylinder"
V0, F = morphkit.read(d / "cylinder-rest.obj")
V1, _ = morphkit.read(d / "cylinder-bend-4.obj")
cyl = new_object("cylinder", V0, F, [("bend", V1)])
activate(cyl)
key = cyl.data.shape_keys.key_blocks["bend"]
key.value = 0.5
check(bpy.ops.morphkit.physical_update() == {"FINISHED"}, "physical_update failed")
got = geometry.key_coords(cyl.data.shape_keys.key_blocks[physical.RESULT_KEY])
F_b, _ = geometry.triangles(cyl.data)
ref = morphkit.PhysicalBlend(geometry.key_coords(cyl.data.shape_keys.key_blocks[0]), [geometry.key_coords(key)], F_b).solve(0.5)
err = float(np.abs(got - ref).max()) / diag(V0)
check(err < 1e-6, f"physical shape key differs from the module by {err} of the diagonal")
results["physical_key_error"] = err
lin = 0.5 * (V0 + V1)
results["physical_vs_linear"] = float(np.abs(got - lin).max()) / diag(V0)
check(results["physical_vs_linear"] > 1e-3, "the physical key equals the linear blend")
render("physical", cyl)

# Live mode: a slider change shows the predictor at once and the equilibrium when the
# background solve is done; a change during the solve is solved next.
def result_key():
    return geometry.key_coords(cyl.data.shape_keys.key_blocks[physical.RESULT_KEY])


ref_blend = morphkit.PhysicalBlend(V0, [V1], F_b)
cyl.morphkit_live = True
check(cyl.morphkit_live_preview, "preview while solving is not the default")
key.value = 0.8
bpy.context.view_layer.update()
physical._live_handler(bpy.context.scene)
check(cyl["morphkit_showing"] == "preview", "live mode does not show the preview first")
err = float(np.abs(result_key() - ref_blend.predict(0.8)).max()) / diag(V0)
check(err < 1e-6, f"the live preview differs from the predictor by {err}")
key.value = 0.9  # moves on while 0.8 is being solved
bpy.context.view_layer.update()
physical._live_handler(bpy.context.scene)
check(physical.finish_live(), "the live solves did not finish")
check(cyl["morphkit_showing"] == "physical", "the equilibrium did not replace the preview")
err = float(np.abs(result_key() - ref_blend.solve(0.9)).max()) / diag(V0)
check(err < 1e-6, f"live update differs by {err}")
results["live_preview_ms"] = float(cyl["morphkit_preview_ms"])
# Without the preview every change waits for its solve.
cyl.morphkit_live_preview = False
key.value = 0.7
bpy.context.view_layer.update()
physical._live_handler(bpy.context.scene)
check(cyl["morphkit_showing"] == "physical", "the synchronous live update shows a preview")
err = float(np.abs(result_key() - ref_blend.solve(0.7)).max()) / diag(V0)
check(err < 1e-6, f"synchronous live update differs by {err}")
cyl.morphkit_live_preview = True
# Interactive while dragging: the interactive shape (within its estimate of the equilibrium)
# first, then the equilibrium once the sliders rest; the same as the module's.
cyl.morphkit_interactive = True
key.value = 0.35
bpy.context.view_layer.update()
physical._live_handler(bpy.context.scene)
job = physical._jobs[cyl.name]
job.join()
physical._poll()
check(cyl["morphkit_showing"] == "interactive", "the interactive shape is not shown first")
fast = morphkit.PhysicalBlend(V0, [V1], F_b)
err = float(np.abs(result_key() - fast.solve(0.35, interactive=True)).max()) / diag(V0)
check(err < 1e-6, f"the interactive shape differs from the module's by {err}")
estimate = float(cyl["morphkit_error_estimate"])
full = ref_blend.solve(0.35)
dist = float(np.linalg.norm(result_key() - full, axis=1).max()) / diag(V0)
check(dist <= estimate + 1e-6, f"the interactive shape is {dist} from the equilibrium, over {estimate}")
check(physical.finish_live(), "the equilibrium after the interactive shape did not finish")
check(cyl["morphkit_showing"] == "physical", "the equilibrium did not replace the interactive shape")
err = float(np.abs(result_key() - full).max()) / diag(V0)
check(err < 1e-6, f"the equilibrium after the interactive shape differs by {err}")
results["live_interactive_ms"] = float(cyl["morphkit_interactive_ms"])
results["live_interactive_estimate"] = estimate
results["live_interactive_error"] = dist
cyl.morphkit_interactive = False
cyl.morphkit_live = False

# Internal springs (the cylinder is closed): the Physical update equals the module's blend with
# a lattice interior; live mode then solves synchronously (the add-on takes no predictor then).
cyl.morphkit_interior = "lattice"
key.value = 0.5
check(bpy.ops.morphkit.physical_update() == {"FINISHED"}, "physical_update with an interior failed")
ref_interior = morphkit.PhysicalBlend(V0, [V1], F_b, interior="lattice")
err = float(np.abs(result_key() - ref_interior.solve(0.5)).max()) / diag(V0)
check(err < 1e-6, f"the physical key with an interior differs from the module by {err}")
check(float(np.abs(result_key() - ref).max()) > 1e-6 * diag(V0), "the interior changed nothing")
cyl.morphkit_live = True
key.value = 0.6
bpy.context.view_layer.update()
physical._live_handler(bpy.context.scene)
check(cyl["morphkit_showing"] == "physical", "live mode with an interior shows a preview")
err = float(np.abs(result_key() - ref_interior.solve(0.6)).max()) / diag(V0)
check(err < 1e-6, f"live update with an interior differs by {err}")
cyl.morphkit_live = False
cyl.morphkit_interior = "none"
results["interior_key_error"] = err

# A pull: an Empty parented to the mesh holds a free vertex.
free = int(np.argmax(np.linalg.norm(V1 - V0, axis=1)))  # moves, so not auto-fixed


def pull_and_update(offset, name):
    """Pulls `free` from its current place by `offset` (an Empty), updates, and checks that it
    sits at the Empty; returns the Empty, the goal and the result."""
    before = geometry.key_coords(cyl.data.shape_keys.key_blocks[physical.RESULT_KEY])
    goal = before[free] + np.asarray(offset) * diag(V0)
    empty = bpy.data.objects.new("pull", None)
    bpy.context.scene.collection.objects.link(empty)
    empty.parent = cyl
    empty.location = tuple(goal)
    empty["morphkit_vertex"] = free
    bpy.context.view_layer.update()
    activate(cyl)
    check(bpy.ops.morphkit.physical_update() == {"FINISHED"}, f"physical_update ({name}) failed")
    after = geometry.key_coords(cyl.data.shape_keys.key_blocks[physical.RESULT_KEY])
    results[name] = float(np.linalg.norm(after[free] - goal)) / diag(V0)
    check(results[name] < 1e-4, f"{name}: the pulled vertex is {results[name]} away")
    return empty, goal, after


empty, _, got = pull_and_update([0.0, 0.0, 0.05], "pull_error")
bpy.data.objects.remove(empty)

# Bake a weight animation over the timeline into a PC2 cache on a Mesh Cache modifier.
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 5
for f, v in ((1, 0.0), (5, 1.0)):
    key.value = v
    key.keyframe_insert("value", frame=f)
activate(cyl)
pc2 = OUT / "cylinder.pc2"
check(bpy.ops.morphkit.physical_bake(filepath=str(pc2)) == {"FINISHED"}, "bake failed")
frames, _, _ = morphkit.read_animation(pc2, reference=d / "cylinder-rest.obj")
check(frames.shape == (5, len(V0), 3), f"baked {frames.shape}")
check("morphkit physical" in cyl.modifiers, "no Mesh Cache modifier")
scene.frame_set(3)
w3 = key.value
err = float(np.abs(frames[2] - morphkit.PhysicalBlend(V0, [V1], F_b).solve(w3)).max()) / diag(V0)
check(err < 1e-6, f"baked frame 3 differs by {err}")
ev = geometry.evaluated_vertices(cyl, bpy.context.evaluated_depsgraph_get())
err = float(np.abs(ev - frames[2]).max()) / diag(V0)
check(err < 1e-6, f"the Mesh Cache shows frame 3 off by {err}")
results["baked_frames"] = int(frames.shape[0])
# A smooth bend does not jump: no vertex group; the group holds a jump's vertices when given.
check(cyl.get("morphkit_jumps") == 0, f"jumps {cyl.get('morphkit_jumps')}")
check(jumps.JUMPS_GROUP not in cyl.vertex_groups, "a jump group after a smooth bake")
jumps.mark(cyl, {"jumps": [{"vertices": [5, 2]}, {"vertices": [2, 9]}]})
group = cyl.vertex_groups[jumps.JUMPS_GROUP]
marked = sorted(v.index for v in cyl.data.vertices if any(g.group == group.index for g in v.groups))
check(marked == [2, 5, 9] and cyl["morphkit_jumps"] == 3, f"jump group {marked}")
jumps.mark(cyl, {"jumps": []})
check(jumps.JUMPS_GROUP not in cyl.vertex_groups, "the jump group was not cleared")
cyl.modifiers.remove(cyl.modifiers["morphkit physical"])

# An obstacle in the bending half's path (Fig. 2): a closed mesh object with morphkit_obstacle.
cyl.data.shape_keys.animation_data_clear()
bar_mesh = bpy.data.meshes.new("bar")
import bmesh  # noqa: E402

bm = bmesh.new()
bmesh.ops.create_cone(bm, cap_ends=True, segments=24, radius1=0.2, radius2=0.2, depth=2.0)
bm.to_mesh(bar_mesh)
bm.free()
bar = bpy.data.objects.new("bar", bar_mesh)
bpy.context.scene.collection.objects.link(bar)
bar.rotation_euler = (np.pi / 2, 0.0, 0.0)  # cone axis z -> y, as the example scene's bar
bar.location = (1.35, 0.0, 0.95)
bar["morphkit_obstacle"] = True
bpy.context.view_layer.update()
key.value = 1.0
activate(cyl)
check(bpy.ops.morphkit.physical_update() == {"FINISHED"}, "physical_update with an obstacle failed")
got = geometry.key_coords(cyl.data.shape_keys.key_blocks[physical.RESULT_KEY])
check(cyl["morphkit_contacts"] > 0, "the bar is not touched")
Vb = geometry.vertices(bar_mesh)
mw = np.array(bar.matrix_world)
obst = morphkit.Obstacle.mesh(Vb @ mw[:3, :3].T + mw[:3, 3], geometry.triangles(bar_mesh)[0])
sb = morphkit.SceneBlend(V0, [V1], F_b, obstacles=[obst])
err = float(np.abs(got - sb.solve(1.0)).max()) / diag(V0)
check(err < 1e-6, f"the obstacle blend differs from the module by {err}")
results["obstacle_contacts"] = int(cyl["morphkit_contacts"])
# The same blend exported as a scene file and replayed by the CLI (when its binary is known).
scene_dir = OUT / "scene"
check(bpy.ops.morphkit.export_scene(directory=str(scene_dir)) == {"FINISHED"}, "export_scene")
check((scene_dir / "scene.toml").exists(), "no scene.toml")
import os  # noqa: E402
import subprocess  # noqa: E402

if os.environ.get("MORPHKIT_BIN"):
    r = subprocess.run(
        [os.environ["MORPHKIT_BIN"], "blend", "--scene", str(scene_dir / "scene.toml"),
         "--out", str(scene_dir / "replay")],
        capture_output=True, text=True,
    )
    check(r.returncode == 0, f"the CLI refused the exported scene: {r.stderr}")
    replay, _, _ = morphkit.read_animation(scene_dir / "replay")
    cur = scene.frame_current - scene.frame_start
    err = float(np.abs(replay[cur] - got).max()) / diag(V0)
    check(err < 1e-5, f"the CLI's replay of the scene differs by {err}")
    results["scene_replay_error"] = err
render("obstacle", cyl, also=[bar])
# A pull and the obstacle together: the pulled vertex sits at its Empty and nothing enters the bar.
empty, goal, got = pull_and_update([0.0, -0.05, 0.0], "pull_with_obstacle_error")
sbp = morphkit.SceneBlend(V0, [V1], F_b, obstacles=[obst], pulls=[(free, [(0.0, tuple(goal))])])
err = float(np.abs(got - sbp.solve(1.0)).max()) / diag(V0)
check(err < 1e-6, f"the pull-and-obstacle blend differs from the module by {err}")
check(sbp.last_stats["collision"]["resolved"], "the pull pushed the tube into the bar")
bpy.data.objects.remove(empty)
bpy.data.objects.remove(bar)

# Latency on the horse (8.4k vertices): one slider change to an updated key.
hc = DATA / "sumner-horse-camel"
H0, HF = morphkit.read(hc / "horse-reference.obj.gz")
H5, _ = morphkit.read(hc / "horse-05.obj.gz")
horse = new_object("horse", H0, HF, [("horse-05", H5)])
activate(horse)
horse.data.shape_keys.key_blocks["horse-05"].value = 0.5
t = time.perf_counter()
bpy.ops.morphkit.physical_update()  # first: builds the solver
results["horse_first_update_ms"] = 1e3 * (time.perf_counter() - t)
horse.data.shape_keys.key_blocks["horse-05"].value = 0.6
t = time.perf_counter()
bpy.ops.morphkit.physical_update()
results["horse_slider_latency_ms"] = 1e3 * (time.perf_counter() - t)
results["horse_solve_ms"] = 1e3 * horse["morphkit_last_stats"]["seconds"]
# Live: the time until the slider shows something (the preview), then the equilibrium.
horse.morphkit_live = True  # shows the preview for 0.6 and starts its solve
check(physical.finish_live(), "the horse's live solve did not finish")
horse.data.shape_keys.key_blocks["horse-05"].value = 0.7
t = time.perf_counter()
bpy.context.view_layer.update()
physical._live_handler(bpy.context.scene)  # (the update's depsgraph handler may have run it)
check(horse["morphkit_showing"] == "preview", "the horse's slider shows no preview")
results["horse_live_preview_ms"] = float(horse["morphkit_preview_ms"])
check(physical.finish_live(), "the horse's live solve did not finish")
results["horse_live_solved_ms"] = 1e3 * (time.perf_counter() - t)
check(horse["morphkit_showing"] == "physical", "the horse's live solve was not shown")
horse.morphkit_live = False
bpy.data.objects.remove(horse)

# --- Transfer and rig transfer: cat -> dog ----------------------------------------------
cd = DATA / "lowpoly-cat-dog"
CS, CF = morphkit.read(cd / "cat-reference.obj")
DT, DF = morphkit.read(cd / "dog-reference.obj")
run, _, _ = morphkit.read_animation(cd / "cat-run")
run = 10.0 * run[:4]  # the run is stored at 0.1x the reference scale (SOURCE.md)
cat = new_object("cat", CS, CF, [(f"run{i}", X) for i, X in enumerate(run)])
dog = new_object("dog", DT, DF)
scene.morphkit_source, scene.morphkit_target = cat, dog
scene.frame_start, scene.frame_end = 1, 4
for i, k in enumerate(cat.data.shape_keys.key_blocks[1:]):
    for f in range(1, 5):
        k.value = 1.0 if f == i + 1 else 0.0
        k.keyframe_insert("value", frame=f)
pairs = json.loads((cd / "markers-cat-dog.json").read_text())["pairs"]
for s, t_ in pairs[:3]:
    check(bpy.ops.morphkit.add_marker(source_vertex=s, target_vertex=t_) == {"FINISHED"}, "add_marker")
from morphkit_blender import transfer_ops  # noqa: E402

check(transfer_ops.read_markers(scene) == pairs[:3], "markers text block")
transfer_ops.write_markers(scene, pairs)
check(bpy.ops.morphkit.transfer() == {"FINISHED"}, "transfer failed")
keys = [k for k in dog.data.shape_keys.key_blocks if k.name.startswith(transfer_ops.FRAME_PREFIX)]
check(len(keys) == 4, f"{len(keys)} frame keys")
check(dog.data.shape_keys.animation_data.action is not None, "no keyframes on the dog")
# The module's answer on the same (float32-stored) coordinates that Blender holds.
DFb, _ = geometry.triangles(dog.data)
CFb, _ = geometry.triangles(cat.data)
CS = geometry.key_coords(cat.data.shape_keys.key_blocks[0])
run = np.stack([geometry.key_coords(k) for k in cat.data.shape_keys.key_blocks[1:]])
DT = geometry.key_coords(dog.data.shape_keys.key_blocks[0])
corr = morphkit.Correspondence.from_markers(CS, CFb, DT, DFb, pairs)
ref = morphkit.Transfer(CS, CFb, DT, DFb, corr).transfer_many(run)
err = max(float(np.abs(geometry.key_coords(k) - r).max()) for k, r in zip(keys, ref)) / diag(DT)
check(err < 1e-6, f"transferred frames differ by {err}")
results["transfer_error"] = err
scene.frame_set(3)
ev = geometry.evaluated_vertices(dog, bpy.context.evaluated_depsgraph_get())
check(float(np.abs(ev - ref[2]).max()) / diag(DT) < 1e-6, "the dog does not show frame 3 at frame 3")
render("transfer", dog)

check(bpy.ops.morphkit.transfer_rig() == {"FINISHED"}, "transfer_rig failed")
names = [k.name for k in dog.data.shape_keys.key_blocks]
check(all(f"run{i}" in names for i in range(4)), f"rig keys {names}")
# The rig transfer is `morphkit rig`'s: its correspondence refined as the library's rig
# default says (off), not as the animation transfer's (issue 55).
rig_defaults = morphkit.rig_defaults()
check(scene.morphkit_rig_refine == rig_defaults["refine"], "the panel's rig refine default is not the library's")
rig_corr = morphkit.Correspondence.from_markers(CS, CFb, DT, DFb, pairs, refine=rig_defaults["refine"])
check(rig_corr.refined == rig_defaults["refine"], "the rig correspondence's refinement")
rig_ref = morphkit.RigTransfer(CS, CFb, DT, DFb, rig_corr).transfer_many(run)
err = max(
    float(np.abs(geometry.key_coords(dog.data.shape_keys.key_blocks[f"run{i}"]) - rig_ref[i]).max())
    for i in range(4)
) / diag(DT)
check(err < 1e-6, f"rig keys differ by {err}")
results["rig_error"] = err
# The panel's options default to the library's (as the module's keywords and the CLI's flags)
# and reach the module as its keyword arguments: off, the configuration before issue 40.
defaults = morphkit.transfer_defaults()
check(scene.morphkit_refine == defaults["refine"], "the panel's refine default is not the library's")
check(scene.morphkit_local_stretch == (defaults["local_stretch"] and defaults["area_weighted"]),
      "the panel's local-stretch default is not the library's")
scene.morphkit_refine = scene.morphkit_local_stretch = False
check(bpy.ops.morphkit.transfer() == {"FINISHED"}, "transfer without refine and local stretch failed")
keys = [k for k in dog.data.shape_keys.key_blocks if k.name.startswith(transfer_ops.FRAME_PREFIX)]
corr_r = morphkit.Correspondence.from_markers(CS, CFb, DT, DFb, pairs, refine=False)
ref_r = morphkit.Transfer(
    CS, CFb, DT, DFb, corr_r, local_stretch=False, area_weighted=False
).transfer_many(run)
check(float(np.abs(ref_r - ref).max()) / diag(DT) > 1e-4, "the options changed nothing")
err = max(float(np.abs(geometry.key_coords(k) - r).max()) for k, r in zip(keys, ref_r)) / diag(DT)
check(len(keys) == 4 and err < 1e-6, f"plain world-frame frames differ by {err}")
results["transfer_local_stretch_error"] = err
scene.property_unset("morphkit_refine")
scene.property_unset("morphkit_local_stretch")
bpy.data.objects.remove(cat)
bpy.data.objects.remove(dog)

# --- Synthesis: flexibility colours and intelligent scribbling ---------------------------
def tube(rings=24, around=10, length=6.0, radius=0.5):
    V = [[length * r / rings, radius * np.cos(2 * np.pi * k / around), radius * np.sin(2 * np.pi * k / around)]
         for r in range(rings + 1) for k in range(around)]
    Fq = []
    for r in range(rings):
        for k in range(around):
            a, b = r * around + k, r * around + (k + 1) % around
            Fq += [[a, b, b + around], [a, b + around, a + around]]
    return np.array(V), np.array(Fq)


def joint(V, angle, at=3.0):
    out = V.copy()
    c, s = np.cos(angle), np.sin(angle)
    right = V[:, 0] > at
    dd = V[right] - [at, 0, 0]
    out[right, 0] = at + c * dd[:, 0] - s * dd[:, 1]
    out[right, 1] = s * dd[:, 0] + c * dd[:, 1]
    return out


TV, TF = tube()
arm = new_object("arm", TV, TF, [(f"j{i}", joint(TV, a)) for i, a in enumerate((0.3, 0.6, 0.9))])
activate(arm)
check(bpy.ops.morphkit.flexibility() == {"FINISHED"}, "flexibility failed")
check("morphkit_flexibility" in arm.data.color_attributes, "no flexibility attribute")
ak = arm.data.shape_keys.key_blocks
flex = morphkit.flexibility(
    geometry.key_coords(ak[0]), geometry.triangles(arm.data)[0], [geometry.key_coords(k) for k in ak[1:]]
)
check(abs(arm["morphkit_flex_max"] - float(flex.max())) < 1e-9 * float(flex.max()), "flex max")
render("flexibility", arm, color_attr=True)
cx = np.array([np.mean([TV[v][0] for v in p.vertices]) for p in arm.data.polygons])
arm.data.polygons.foreach_set("select", ((cx > 3.8) & (cx < 5.6)).tolist())
check(bpy.ops.morphkit.refine_scribble() == {"FINISHED"}, "refine_scribble failed")
sel = np.array([p.select for p in arm.data.polygons])
check(sel[cx > 4.0].all() and not sel[cx < 2.0].any(), "refined selection is not the right half")
scribble = json.loads(bpy.data.texts["morphkit_scribble.json"].as_string())
check(len(scribble["triangles"]) == arm["morphkit_selected_triangles"], "scribble text block")
render("partitions", arm, color_attr=True)
results["selected_triangles"] = int(arm["morphkit_selected_triangles"])

# Pose modification: turn the selected (right) part by 0.6 rad about z.
check(bpy.ops.morphkit.rotate_partition(axis=(0, 0, 1), angle=0.6) == {"FINISHED"}, "rotate_partition")
posed = geometry.key_coords(arm.data.shape_keys.key_blocks["morphkit_pose"])
Fa, Pa = geometry.triangles(arm.data)
base_a = geometry.key_coords(ak[0])
parts = morphkit.Partitions(base_a, Fa, flex)
ref_pose = parts.edit_pose(sel[Pa], (0.0, 0.0, 1.0), 0.6)
err = float(np.abs(posed - ref_pose).max()) / diag(TV)
check(err < 1e-6, f"posed key differs by {err}")
check(float(np.abs(posed - base_a).max()) > 0.1 * diag(TV), "the pose did not turn")
results["pose_error"] = err
arm.data.shape_keys.key_blocks["morphkit_pose"].value = 1.0
render("pose", arm)

# --- Baked physical correctives (issue 56): shape keys with drivers, played without the add-on
import inspect  # noqa: E402

from morphkit_blender import bake_ops  # noqa: E402


def bulge(V, at=3.0, width=0.8, amount=0.35):
    out = V.copy()
    f = 1.0 + amount * np.clip(1.0 - np.abs(V[:, 0] - at) / width, 0.0, None)
    out[:, 1:] *= f[:, None]
    return out


BV, BF = tube(rings=16, around=8)
SLIDERS = ["bendA", "bendB", "bulge"]
rig_obj = new_object("baked", BV, BF, list(zip(SLIDERS, [
    joint(BV, 0.9, at=2.0), joint(BV, -0.9, at=4.0), bulge(BV)])))
rkeys = rig_obj.data.shape_keys.key_blocks
rkeys["bendA"].value = 0.25
op_props = bpy.ops.morphkit.bake_correctives.get_rna_type().properties
for name, p in inspect.signature(morphkit.PhysicalBlend.bake).parameters.items():
    if name in ("inbetweens", "pair_tolerance", "max_pairs", "damping", "inbetween_tolerance"):
        check(abs(op_props[name].default - p.default) <= 1e-6 * abs(p.default),
              f"the operator's {name} default is not the module's")
Bb = geometry.key_coords(rkeys[0])
Fb, _ = geometry.triangles(rig_obj.data)
SETTINGS = [(0.3, 0.0, 0.0), (0.0, 0.55, 0.0), (0.0, 0.0, 0.93), (0.7, 0.9, 0.0),
            (0.4, 0.8, 1.0), (1.3, 0.0, 0.0), (0.6, 1.2, 0.2), (-0.2, 0.5, 0.0)]


def bake_and_check(**options):
    """Bakes `rig_obj` with the operator, checks its keys and drivers against the module's
    bake; returns (BakedRig, the keys in shape_weights' order)."""
    activate(rig_obj)
    check(bpy.ops.morphkit.bake_correctives(threads=2, **options) == {"FINISHED"}, "bake failed")
    blend = morphkit.PhysicalBlend(Bb, [geometry.key_coords(rkeys[s]) for s in SLIDERS], Fb)
    rig = blend.bake(threads=2, **options)
    added = rig.num_shapes - len(SLIDERS)
    check(len(rig.combinations) >= 1, "the test rig has no combination shape")
    check(len(rkeys) == 1 + len(SLIDERS) + added, f"{len(rkeys)} keys for {rig.num_shapes} shapes")
    check(len(rig_obj["morphkit_bake"]["shapes"]) == added, "the bake's record of its keys")
    order, shapes = [], []
    for t, (s, ws) in enumerate(zip(SLIDERS, rig.inbetween_weights)):
        for k, w in enumerate(ws):
            order.append(s if k == len(ws) - 1 else f"{s}@{bake_ops.short(w)}")
            shapes.append(rig.inbetween(t, k))
    for c, ((i, j), levels) in enumerate(zip(rig.combinations, rig.combination_levels)):
        for level, w in enumerate(levels):
            order.append(f"{SLIDERS[i]}+{SLIDERS[j]}@{bake_ops.short(w)}")
            shapes.append(rig.combination(c, level))
    check(all(n in rkeys for n in order), f"keys {list(rkeys.keys())}, expected {order}")
    err = max(float(np.abs(geometry.key_coords(rkeys[n]) - Bb - d).max()) for n, d in zip(order, shapes))
    check(err / diag(BV) < 1e-6, f"baked keys differ from the module's shapes by {err}")
    drivers = {fc.data_path: fc.driver for fc in rig_obj.data.shape_keys.animation_data.drivers}
    for n in order:
        d = drivers.get(f'key_blocks["{n}"].value')
        check(d is not None and d.is_valid and d.is_simple_expression, f"{n}'s driver is not simple")
        check(rkeys[n].slider_min == -10.0 and rkeys[n].slider_max == 10.0, f"{n}'s slider range")
    return rig, order


def play_baked(obj, rig, order, what):
    """Sets the sliders' properties, and checks the keys' values and the evaluated mesh."""
    worst = 0.0
    for x in SETTINGS:
        for s, v in zip(SLIDERS, x):
            obj[f"mk_{s}"] = v
        obj.update_tag()  # as the UI does for a property edited there (a script's own job)
        bpy.context.view_layer.update()
        x32 = [float(np.float32(v)) for v in x]  # what the drivers read
        want = rig.shape_weights(x32)
        keys = obj.data.shape_keys.key_blocks
        got = [keys[n].value for n in order]
        check(np.allclose(got, want, rtol=0, atol=1e-5), f"{what}: key values at {x}: {got} {want}")
        ev = geometry.evaluated_vertices(obj, bpy.context.evaluated_depsgraph_get())
        err = float(np.abs(ev - rig.evaluate(x32)).max()) / diag(BV)
        check(err < 1e-6, f"{what}: the baked rig at {x} is {err} off BakedRig.evaluate")
        worst = max(worst, err)
    return worst


# An animation of a slider (keyframes on its key's value, Bezier with a linear last key),
# which the drivers would hide: the bake moves it onto the slider's property.
rkeys["bulge"].value = 0.0
rig_obj.data.shape_keys.keyframe_insert(data_path='key_blocks["bulge"].value', frame=1)
rkeys["bulge"].value = 0.8
rig_obj.data.shape_keys.keyframe_insert(data_path='key_blocks["bulge"].value', frame=21)
bake_ops._fcurve(rig_obj.data.shape_keys, 'key_blocks["bulge"].value')[0].keyframe_points[1].interpolation = "LINEAR"
rkeys["bulge"].value = 0.0
# A bake with damping and 3 in-betweens, then baked again (replaced) with the defaults.
rig, order = bake_and_check(damping=2.0, inbetweens=3)
check(abs(rig_obj["mk_bendA"] - 0.25) < 1e-7, "the slider's property starts at the key's value")
moved, _ = bake_ops._fcurve(rig_obj, '["mk_bulge"]')
check(moved is not None and np.allclose([tuple(p.co) for p in moved.keyframe_points], [(1, 0), (21, 0.8)])
      and moved.keyframe_points[1].interpolation == "LINEAR",
      f"the slider's keyframes moved: {moved and [(tuple(p.co), p.interpolation) for p in moved.keyframe_points]}")
check(bake_ops._fcurve(rig_obj.data.shape_keys, 'key_blocks["bulge"].value')[0] is None,
      "the key keeps no keyframes under its driver")
bpy.context.scene.frame_set(21)
check(abs(rig_obj["mk_bulge"] - 0.8) < 1e-6 and abs(rkeys["bulge"].value - rig.shape_weights([0.25, 0.0, 0.8])[order.index("bulge")]) < 1e-5,
      "the animation plays the baked rig")
bpy.context.scene.frame_set(1)
results["bake_damped_error"] = play_baked(rig_obj, rig, order, "damped")
rig, order = bake_and_check()
check("bendA@0.125" in rkeys and "bendA@0.25" in rkeys, "the default in-betweens' keys")
results["bake_shapes_added"] = rig.num_shapes - len(SLIDERS)
results["bake_error"] = play_baked(rig_obj, rig, order, "with the add-on")
# The physical tools read a baked rig's sliders from its properties and hide its added keys.
activate(rig_obj)
check(bpy.ops.morphkit.physical_update() == {"FINISHED"}, "physical_update on the baked rig")
solved = geometry.key_coords(rkeys[physical.RESULT_KEY])
x = [float(np.float32(v)) for v in SETTINGS[-1]]
ref = morphkit.PhysicalBlend(Bb, [geometry.key_coords(rkeys[s]) for s in SLIDERS], Fb).solve(x)
check(float(np.abs(solved - ref).max()) / diag(BV) < 1e-6, "the baked rig's physical solve")
check(all(rkeys[n].mute for n in order), "the baked keys are shown under the solve")
check(bpy.ops.morphkit.physical_linear() == {"FINISHED"}, "physical_linear on the baked rig")
check(not any(rkeys[n].mute for n in order), "the baked keys are muted after Linear")
# Without the add-on and with Python drivers off (--factory-startup has auto-run off too):
# the saved file opened without trusting it; a driver that needs Python stays blocked.
probe = bpy.data.objects.new("autoexec_probe", None)
bpy.context.scene.collection.objects.link(probe)
probe["v"] = 0.0
probe.driver_add('["v"]').driver.expression = "bpy.context.scene.frame_current ** 2 + 1"
baked_file = OUT / "baked.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(baked_file))
bpy.ops.preferences.addon_disable(module="morphkit_blender")
bpy.ops.wm.open_mainfile(filepath=str(baked_file), use_scripts=False)
bpy.context.scene.frame_set(3)
check(bpy.data.objects["autoexec_probe"]["v"] != 10.0 and bpy.app.autoexec_fail,
      "Python drivers ran: the check without auto-run proves nothing")
results["bake_error_no_addon"] = play_baked(bpy.data.objects["baked"], rig, order, "no add-on")

(OUT / "results.json").write_text(json.dumps(results, indent=2))
print("MORPHKIT ADDON TESTS PASSED", json.dumps(results))
