"""Blender meshes as numpy arrays (V (n, 3) float64, F (m, 3) int64) and back."""

import numpy as np


def triangles(mesh):
    """Loop triangles of `mesh` as (F, polygon_of_triangle)."""
    mesh.calc_loop_triangles()
    m = len(mesh.loop_triangles)
    F = np.empty(3 * m, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", F)
    P = np.empty(m, dtype=np.int32)
    mesh.loop_triangles.foreach_get("polygon_index", P)
    return F.reshape(m, 3).astype(np.int64), P


def vertices(mesh):
    """Vertex coordinates (object space) of `mesh`."""
    V = np.empty(3 * len(mesh.vertices), dtype=np.float64)
    mesh.vertices.foreach_get("co", V)
    return V.reshape(-1, 3)


def key_coords(key_block):
    """Coordinates of one shape key."""
    V = np.empty(3 * len(key_block.data), dtype=np.float64)
    key_block.data.foreach_get("co", V)
    return V.reshape(-1, 3)


def set_key_coords(key_block, V):
    key_block.data.foreach_set("co", np.ascontiguousarray(V, dtype=np.float32).ravel())


def evaluated_vertices(obj, depsgraph):
    """Vertices of `obj` after shape keys and modifiers (vertex count must be unchanged)."""
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        return vertices(mesh)
    finally:
        ev.to_mesh_clear()


def ensure_key(obj, name, from_mix=False):
    """The shape key `name` of `obj`, created (with a Basis) when missing."""
    if obj.data.shape_keys is None:
        obj.shape_key_add(name="Basis", from_mix=False)
    key = obj.data.shape_keys.key_blocks.get(name)
    if key is None:
        key = obj.shape_key_add(name=name, from_mix=from_mix)
    return key


def face_colors(mesh, name, tri_values, tri_to_poly, colormap):
    """A colour attribute (face corners, which Blender's viewport shows) from per-triangle
    values: a polygon takes the value of its first triangle, mapped by
    `colormap(values) -> (k, 4)`. It becomes the active (shown) colour attribute."""
    poly_values = np.zeros(len(mesh.polygons))
    poly_values[tri_to_poly[::-1]] = tri_values[::-1]
    totals = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", totals)
    colors = np.repeat(colormap(poly_values), totals, axis=0)
    attr = mesh.color_attributes.get(name)
    if attr is None:
        attr = mesh.color_attributes.new(name=name, type="FLOAT_COLOR", domain="CORNER")
    attr.data.foreach_set("color", np.ascontiguousarray(colors, dtype=np.float32).ravel())
    mesh.color_attributes.active_color = attr
    return attr


def viridis_like(values):
    """A perceptual dark-blue → yellow ramp for values scaled to [0, 1]."""
    v = np.asarray(values, dtype=float)
    hi = v.max() if v.size and v.max() > 0 else 1.0
    t = np.clip(v / hi, 0.0, 1.0)[:, None]
    lo_c = np.array([0.267, 0.005, 0.329])
    mid_c = np.array([0.128, 0.567, 0.551])
    hi_c = np.array([0.993, 0.906, 0.144])
    rgb = np.where(t < 0.5, lo_c + (mid_c - lo_c) * (2 * t), mid_c + (hi_c - mid_c) * (2 * t - 1))
    return np.hstack([rgb, np.ones((len(v), 1))])
