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
equilibrium the "Physical" button gives; only when it is shown depends on time. With
"Interactive while dragging" the background job first gives the rig's interactive shape (tens
of milliseconds, within its error estimate of the equilibrium; the rig is prepared once, a
minute for ten targets, and kept next to a saved .blend file), and the equilibrium replaces it
once the sliders rest for `SETTLE_SECONDS`.
"""

import os
import threading
import time

import bpy
import numpy as np

from . import geometry

RESULT_KEY = "morphkit_physical"
BAKE_PROP = "morphkit_bake"  # a baked rig's record: sliders, their properties, the added keys
_solvers = {}  # object name -> (signature, PhysicalBlend, F, Predictor)
_last = {}  # object name -> weights and pulls last solved or asked for
_busy = [False]
_jobs = {}  # object name -> _Job solving on a background thread
_wanted = {}  # object name -> (state, blend, weights, pulls) newest live request
_settling = {}  # object name -> when its interactive shape was shown (equilibrium due)
POLL_SECONDS = 0.05
SETTLE_SECONDS = 0.3  # sliders at rest this long: the equilibrium replaces the interactive shape


def morphkit_module():
    import morphkit

    return morphkit


def target_keys(obj):
    """The rig's targets (its sliders): every shape key but the base, the result key and the
    keys a bake added (bake_ops)."""
    keys = obj.data.shape_keys.key_blocks
    baked = set(obj[BAKE_PROP].get("shapes", ())) if BAKE_PROP in obj else ()
    return [k for k in keys[1:] if k.name != RESULT_KEY and k.name not in baked]


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
    """The sliders' weights: the targets' values, or a baked rig's slider properties."""
    if BAKE_PROP in obj:
        return [float(obj.get(p, 0.0)) for p in obj[BAKE_PROP]["properties"]]
    return [k.value for k in target_keys(obj)]


def _shown_keys(obj):
    """The keys that the result key replaces: the targets and a bake's added keys."""
    return [k for k in obj.data.shape_keys.key_blocks[1:] if k.name != RESULT_KEY]


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
    for k in _shown_keys(obj):
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
    """One live solve on a background thread (the solve releases the GIL): the full
    equilibrium, or with `prepare` (the arguments of `prepare_interactive`) the interactive
    shape, the rig's interactive space prepared first where it is not yet."""

    def __init__(self, name, state, blend, w, pulls, prepare=None):
        super().__init__(daemon=True, name=f"morphkit live {name}")
        self.state, self.blend, self.w, self.pulls = state, blend, w, pulls
        self.prepare = prepare
        self.out = self.error = None
        self.started_at = time.perf_counter()
        self.seconds = 0.0
        self.start()

    def run(self):
        try:
            if self.prepare is None:
                self.out = _solve(self.blend, self.w, self.pulls)
            else:
                self.blend.prepare_interactive(**self.prepare)
                t0 = time.perf_counter()
                X = self.blend.solve(self.w, interactive=True)
                self.started_at = t0  # the latency of the shape, not of the preparation
                self.out = (X, self.blend.last_stats, None)
        except Exception as e:  # reported on the main thread
            self.error = e
        self.seconds = time.perf_counter() - self.started_at


def _interactive(obj, blend, pulls):
    """`prepare_interactive`'s arguments where live mode shows `obj`'s interactive shape
    before its equilibrium (a surface blend without pulls, the option on), else None. The
    preparation is kept next to a saved .blend file, so that reopening it costs seconds."""
    if not getattr(obj, "morphkit_interactive", False) or pulls:
        return None
    if not isinstance(blend, morphkit_module().PhysicalBlend) or _solvers[obj.name][3] is None:
        return None
    cache = None
    if bpy.data.filepath:
        cache = bpy.path.abspath(f"//{bpy.path.clean_name(obj.name)}.mkinteractive")
    return {"threads": os.cpu_count() or 1, "cache": cache}


def _start(name, wanted):
    """Starts the live job for `wanted`: the interactive shape first where it is on."""
    obj = bpy.data.objects.get(name)
    prepare = None if obj is None else _interactive(obj, wanted[1], wanted[3])
    _jobs[name] = _Job(name, *wanted, prepare=prepare)


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
    _settling.pop(obj.name, None)
    if obj.name not in _jobs:
        _start(obj.name, _wanted[obj.name])
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=POLL_SECONDS)


def _poll(settle_now=False):
    """Timer: shows finished jobs that are still wanted and starts the newest request; an
    interactive shape is replaced by the equilibrium once the sliders rest for
    `SETTLE_SECONDS` (at once with `settle_now`)."""
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
            if job.prepare is not None:
                _show_interactive(obj, job)
                _settling[name] = time.perf_counter()
                continue
            _wanted.pop(name)
            _show_solved(obj, job.out)
            obj["morphkit_latency_ms"] = 1e3 * job.seconds
        else:  # the sliders moved on while this job solved: solve the newest values
            _start(name, wanted)
    now = time.perf_counter()
    for name, since in list(_settling.items()):
        if name in _jobs or name not in _wanted:
            _settling.pop(name)
        elif settle_now or now - since >= SETTLE_SECONDS:
            _settling.pop(name)
            _jobs[name] = _Job(name, *_wanted[name])  # the equilibrium of the same sliders
    return POLL_SECONDS if _jobs or _settling else None


def _show_interactive(obj, job):
    X, stats, _ = job.out
    _show(obj, X, "interactive")
    obj["morphkit_interactive_ms"] = 1e3 * job.seconds
    if stats.get("error_estimate") is not None:
        obj["morphkit_error_estimate"] = stats["error_estimate"]


def _settle(name):
    """Waits for `name`'s live job (the blend serves one solve at a time) and drops it."""
    job = _jobs.pop(name, None)
    if job is not None:
        job.join()
    _wanted.pop(name, None)
    _settling.pop(name, None)


def finish_live(timeout=300.0):
    """Waits for the live jobs and shows their results (for scripts and `blender -b`, where
    timers do not run). Returns whether everything finished within `timeout` seconds."""
    deadline = time.perf_counter() + timeout
    while _jobs or _settling:
        for job in list(_jobs.values()):
            job.join(max(0.0, deadline - time.perf_counter()))
        if any(j.is_alive() for j in _jobs.values()):
            return False
        _poll(settle_now=True)
    return True


def show_linear(obj):
    if obj.data.shape_keys is None:
        return
    for k in _shown_keys(obj):
        k.mute = False
    key = obj.data.shape_keys.key_blocks.get(RESULT_KEY)
    if key is not None:
        key.value = 0.0
        key.mute = True
    obj.data.update()


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
