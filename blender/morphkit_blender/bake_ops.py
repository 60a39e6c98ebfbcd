"""Bake physical correctives (issue 56): the physical blend of the object's shape keys baked
into in-between and combination shape keys (`PhysicalBlend.bake`), played by drivers.

The rig's targets are its sliders. The bake adds a shape key per in-between (`NAME@0.125`, …;
the one at 1 is the target's own key) and per combination level (`A+B@1`, `A+B@4`), and one
custom property per slider on the object (`mk_NAME`, soft range 0–1) that an artist keys or
drives instead of the shape-key values. Every shape key of the rig, the targets included, gets
a driver computing its weight from those properties exactly as docs/bake.md's mapping does
(`BakedRig.shape_weights`): a piecewise-linear hat over the in-between weights, and for a
combination the same hat over its levels at `φ = 4 xᵢ xⱼ`. The drivers are Blender's "simple
expressions" (min, max, arithmetic, and `pow` only when the damping is not 0), which Blender
evaluates without Python: the rig plays with "Auto Run Python Scripts" off and without this
add-on. Shape-key values may leave [0, 1] (the hat's end segments extend), so every key's
slider range is Blender's whole [-10, 10], and each property's hard range is where its keys'
weights stay inside it. Keyframes on a target's value (an animation of the sliders) move onto
its property, since a driven value would hide them; an unbake moves them back.
"""

import math
import os

import bpy

from . import geometry
from .physical import BAKE_PROP, RESULT_KEY, _settle, show_linear, solver_for, target_keys

PREFIX = "mk_"  # a slider's custom property: PREFIX + the target's name
LIMIT = 10.0  # Blender's limit on a shape key's value (slider_min/slider_max)


def _num(v):
    return repr(float(v))


def short(w):
    """A weight in a shape key's name, as the glTF writer names its targets (`asset_bake.rs`:
    four decimals, trailing zeros dropped): `0.125`, `1`."""
    return f"{w:.4f}".rstrip("0").rstrip(".")


def hat_expressions(weights, x):
    """Per shape of a hat over `weights` (increasing, > 0), the expression of its weight in
    the expression `x`: the upper shape of the segment holding x weighs `s = (x − a)/(b − a)`,
    the lower `1 − s`; the first segment starts at 0, the end segments extend (below 0 the
    first shape goes negative, beyond the last weight the last two go on linearly)."""
    n = len(weights)
    out = []
    for k in range(n):
        a = weights[k - 1] if k > 0 else 0.0
        b = weights[k]
        rise = f"{x}/{_num(b)}" if k == 0 else f"({x}-{_num(a)})/{_num(b - a)}"
        left = rise if k == 0 else f"max(0,{rise})"
        if k == n - 1:
            out.append(left)
            continue
        c = weights[k + 1]
        fall = f"1-({x}-{_num(b)})/{_num(c - b)}"
        right = fall if k == n - 2 else f"max(0,{fall})"
        out.append(f"min({left},{right})")
    return out


def combination_expression(i, j, damping, n):
    """The combination weight φ of sliders `i` and `j` over the variables `s0`, `s1`, …:
    `4 xᵢ xⱼ ((xᵢ + xⱼ)/Σ max(x, 0))^damping`, 0 unless both are positive."""
    a, b = f"max(s{i},0)", f"max(s{j},0)"
    phi = f"4*{a}*{b}"
    if damping != 0.0:
        total = "+".join(f"max(s{k},0)" for k in range(n))
        phi += f"*pow(min(({a}+{b})/max({total},1e-300),1),{_num(damping)})"
    return f"({phi})"


def _upper(weights):
    """The largest argument of a hat over `weights` whose shapes stay within ±LIMIT."""
    if len(weights) == 1:
        return LIMIT * weights[0]
    a = weights[-2]
    return a + LIMIT * (weights[-1] - a)


def slider_ranges(rig):
    """Per slider the (min, max) of its property: every driven key stays within ±LIMIT."""
    out = []
    for t, w in enumerate(rig.inbetween_weights):
        hi = _upper(w)
        for (i, j), levels in zip(rig.combinations, rig.combination_levels):
            if t in (i, j):
                hi = min(hi, math.sqrt(_upper(levels) / 4.0))
        out.append((-LIMIT * w[0], hi))
    return out


def _path(name):
    return f'key_blocks["{bpy.utils.escape_identifier(name)}"].value'


def _drive(key, kb, expression, variables, obj):
    """Drives `kb.value` by `expression` over `variables` {name: custom property}."""
    kb.driver_remove("value")
    fc = key.driver_add(_path(kb.name))
    drv = fc.driver
    drv.type = "SCRIPTED"
    for name, prop in variables.items():
        var = drv.variables.new()
        var.name = name
        var.type = "SINGLE_PROP"
        var.targets[0].id_type = "OBJECT"
        var.targets[0].id = obj
        var.targets[0].data_path = f'["{bpy.utils.escape_identifier(prop)}"]'
    drv.expression = expression
    kb.slider_min, kb.slider_max = -LIMIT, LIMIT
    return fc


def _fcurve(id_data, path):
    """The F-curve animating `path` on `id_data`, and the collection holding it (to remove it
    from): an action's own `fcurves` (Blender up to 4.x), or the channel bags of a layered
    action (4.4 and later); (None, None) when `path` is not keyed."""
    ad = id_data.animation_data
    action = ad.action if ad is not None else None
    if action is None:
        return None, None
    bags = [getattr(action, "fcurves", None)]
    for layer in getattr(action, "layers", ()):
        for strip in getattr(layer, "strips", ()):
            bags.extend(bag.fcurves for bag in getattr(strip, "channelbags", ()))
    for fcurves in bags:
        if fcurves is None:
            continue
        for fc in fcurves:
            if fc.data_path == path:
                return fc, fcurves
    return None, None


def move_keyframes(src, src_path, dst, dst_path, store):
    """Moves the keyframes of `src_path` on `src` onto `dst_path` on `dst` (frame, value,
    interpolation and handles kept; `store(value)` sets the destination's value before each
    insert) and removes them from `src`. Returns how many moved."""
    fc, fcurves = _fcurve(src, src_path)
    if fc is None:
        return 0
    points = [
        (tuple(p.co), p.interpolation, p.handle_left_type, p.handle_right_type,
         tuple(p.handle_left), tuple(p.handle_right))
        for p in fc.keyframe_points
    ]
    for (frame, value), *_ in points:
        store(value)
        dst.keyframe_insert(data_path=dst_path, frame=frame)
    new, _ = _fcurve(dst, dst_path)
    if new is not None and len(new.keyframe_points) == len(points):
        for q, (co, interp, hl_type, hr_type, hl, hr) in zip(new.keyframe_points, points):
            q.co = co
            q.interpolation = interp
            q.handle_left_type, q.handle_right_type = hl_type, hr_type
            q.handle_left, q.handle_right = hl, hr
        new.update()
    fcurves.remove(fc)
    return len(points)


def unbake(obj):
    """Removes a previous bake of `obj`: its shape keys, drivers and properties (the sliders'
    values stay in their keys)."""
    info = obj.get(BAKE_PROP)
    if info is None:
        return
    key = obj.data.shape_keys
    if key is not None:
        for name in list(info.get("sliders", ())) + list(info.get("shapes", ())):
            if name in key.key_blocks:
                key.driver_remove(_path(name))
        for name in info.get("shapes", ()):
            kb = key.key_blocks.get(name)
            if kb is not None:
                obj.shape_key_remove(kb)
        for name, prop in zip(info.get("sliders", ()), info.get("properties", ())):
            kb = key.key_blocks.get(name)
            if kb is not None and prop in obj:
                kb.value = max(kb.slider_min, min(kb.slider_max, float(obj[prop])))
                # The slider's animation goes back onto its key, as it was before the bake.
                move_keyframes(
                    obj, f'["{bpy.utils.escape_identifier(prop)}"]', key, _path(name),
                    lambda v, kb=kb: setattr(kb, "value", v),
                )
    for prop in info.get("properties", ()):
        if prop in obj:
            del obj[prop]
    del obj[BAKE_PROP]


def bake_into_keys(obj, options):
    """Bakes `obj`'s rig (`options`: `PhysicalBlend.bake`'s keywords) into shape keys driven
    by one custom property per slider; returns the BakedRig."""
    unbake(obj)
    if getattr(obj, "morphkit_live", False):
        obj.morphkit_live = False
    _settle(obj.name)
    show_linear(obj)
    key = obj.data.shape_keys
    result = key.key_blocks.get(RESULT_KEY)
    if result is not None:  # the add-on's display of a solve, no part of the rig
        obj.shape_key_remove(result)
    sliders = [k.name for k in target_keys(obj)]
    values = [k.value for k in target_keys(obj)]
    blend, _ = solver_for(obj)  # a surface PhysicalBlend of the keys, as the operators build
    rig = blend.bake(**options)
    base = geometry.key_coords(key.key_blocks[0])
    props = [PREFIX + s for s in sliders]
    for p, v, (lo, hi), s in zip(props, values, slider_ranges(rig), sliders):
        obj[p] = min(max(float(v), lo), hi)
        obj.id_properties_ui(p).update(
            default=0.0, min=lo, max=hi, soft_min=0.0, soft_max=1.0,
            description=f"Slider of the baked physical rig: drives '{s}' and its correctives",
        )
        # The key's value is driven from now on, which would hide its animation: the
        # artist's keyframes move onto the slider's property and play the baked rig.
        move_keyframes(
            key, _path(s), obj, f'["{bpy.utils.escape_identifier(p)}"]',
            lambda v, p=p: obj.__setitem__(p, v),
        )
        obj[p] = min(max(float(v), lo), hi)
    shapes = []

    def add(name, delta):
        kb = obj.shape_key_add(name=name, from_mix=False)  # a new key (a free name)
        kb.relative_key = key.key_blocks[0]
        geometry.set_key_coords(kb, base + delta)
        shapes.append(kb.name)
        return kb

    for t, (s, weights) in enumerate(zip(sliders, rig.inbetween_weights)):
        exprs = hat_expressions(weights, "x")
        for k, w in enumerate(weights):
            last = k == len(weights) - 1
            kb = key.key_blocks[s] if last else add(f"{s}@{short(w)}", rig.inbetween(t, k))
            _drive(key, kb, exprs[k], {"x": props[t]}, obj)
    n = len(sliders)
    damping = rig.damping
    for c, ((i, j), levels) in enumerate(zip(rig.combinations, rig.combination_levels)):
        phi = combination_expression(i, j, damping, n)
        used = range(n) if damping != 0.0 else (i, j)
        variables = {f"s{k}": props[k] for k in used}
        for level, (w, expr) in enumerate(zip(levels, hat_expressions(levels, phi))):
            kb = add(f"{sliders[i]}+{sliders[j]}@{short(w)}", rig.combination(c, level))
            _drive(key, kb, expr, variables, obj)
    obj[BAKE_PROP] = {"sliders": sliders, "properties": props, "shapes": shapes}
    obj.data.update()
    return rig


class MORPHKIT_OT_bake_correctives(bpy.types.Operator):
    """Bake the physical blend of the shape keys into in-between and combination shape keys,
    driven by one custom property per slider (mk_NAME): the rig then plays the physical look
    with drivers only, without this add-on or Python scripts"""

    bl_idname = "morphkit.bake_correctives"
    bl_label = "Bake physical correctives"
    bl_options = {"REGISTER", "UNDO"}

    # The defaults are PhysicalBlend.bake's (the library's BakeOptions; checked by the tests).
    inbetweens: bpy.props.IntProperty(
        name="In-betweens", description="In-between shapes per target, at k / (n + 1)",
        default=7, min=0, max=63,
    )
    pair_tolerance: bpy.props.FloatProperty(
        name="Pair tolerance", description="A pair of targets gets a combination shape when its "
        "correction passes this fraction of the bounding-box diagonal", default=1e-4, min=0.0,
        precision=6,
    )
    max_pairs: bpy.props.IntProperty(
        name="Max pairs", description="At most this many combination shapes (the pairs that "
        "move a vertex farthest)", default=120, min=0,
    )
    inbetween_tolerance: bpy.props.FloatProperty(
        name="In-between tolerance", description="More in-betweens where a target's "
        "interpolation is farther than this fraction of the bounding-box diagonal from its "
        "physical equilibrium (0: the regular ones only)", default=1e-3, min=0.0, precision=6,
    )
    damping: bpy.props.FloatProperty(
        name="Damping", description="Exponent of the combination weights' damping by the "
        "pair's share of all weights (0: none)", default=0.0, min=0.0,
    )
    threads: bpy.props.IntProperty(
        name="Threads", description="Solves in parallel (the result does not depend on it)",
        default=max(1, os.cpu_count() or 1), min=1, max=256,
    )

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return (
            obj is not None and obj.type == "MESH" and obj.data.shape_keys is not None
            and len(obj.data.shape_keys.key_blocks) >= 2
        )

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        import morphkit

        obj = context.active_object
        options = {
            "inbetweens": self.inbetweens, "pair_tolerance": self.pair_tolerance,
            "max_pairs": self.max_pairs, "damping": self.damping, "threads": self.threads,
            "inbetween_tolerance": self.inbetween_tolerance,
        }
        try:
            rig = bake_into_keys(obj, options)
        except morphkit.MorphkitError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        added = len(obj[BAKE_PROP]["shapes"])
        self.report(
            {"INFO"}, f"baked {added} shape keys ({len(rig.combinations)} combinations); "
            f"the sliders are the object's properties {PREFIX}*",
        )
        return {"FINISHED"}


classes = (MORPHKIT_OT_bake_correctives,)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
