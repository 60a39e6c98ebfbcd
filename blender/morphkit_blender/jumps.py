"""Jumps between baked frames: where a part snapped from one equilibrium of the springs to
another (``morphkit.continuity``; see the README, "Jumps between frames")."""

JUMPS_GROUP = "morphkit jumps"


def linear_frames(base, targets, rows):
    """The linear blend ``base + Σ w (target − base)`` (arrays ``(n, 3)``) for each row of delta
    weights."""
    deltas = [t - base for t in targets]
    return [base + sum(w * d for w, d in zip(row, deltas)) for row in rows]


def mark(obj, continuity):
    """Puts the vertices of every jump in `continuity` (``morphkit.continuity``) into the vertex
    group ``morphkit jumps`` (removed when nothing jumped), and their count in
    ``obj["morphkit_jumps"]``."""
    old = obj.vertex_groups.get(JUMPS_GROUP)
    if old is not None:
        obj.vertex_groups.remove(old)
    region = sorted({v for j in continuity["jumps"] for v in j["vertices"]})
    obj["morphkit_jumps"] = len(region)
    if region:
        obj.vertex_groups.new(name=JUMPS_GROUP).add(region, 1.0, "REPLACE")
