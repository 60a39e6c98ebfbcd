"""Renders the OBJs of `cargo run --example tail_twist -- DIR` (issue 40, a tail curled far)
as one PNG: one row per case and directory (before / after a change) with the curled
shape and, at α = ½, the linear blend, the predictor and the solve (the rest shape is the
straight tube), seen from above the plane of the curl.

Triangles facing against both shapes (normal more than 120° from each, as
`springs::metrics::fold_metrics` counts them) are red; the strip of triangles along the
top of the straight tube (+z) is dark blue, so a twist about the tube's axis shows as a helix.

    python3 tools/render_tail.py OUT.png DIR_BEFORE [DIR_AFTER ...]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402
from render_compare import read_obj  # noqa: E402  (same folder)

AROUND = 12  # vertices per ring of the generated tube (tests/common/tail.rs)


def normals(v, f):
    return np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])


def flipped(v, f, ends):
    n = normals(v, f)
    out = np.ones(len(f), bool)
    for e in ends:
        m = normals(e, f)
        dots = (n * m).sum(1)
        out &= dots < -0.5 * np.linalg.norm(n, axis=1) * np.linalg.norm(m, axis=1)
    return out


def draw(ax, v, f, ends, title, box):
    n = normals(v, f)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = np.array([0.3, -0.5, 0.8])
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.abs(n @ light)
    colors = np.stack([shade * 0.85, shade * 0.85, shade * 0.8, np.ones_like(shade)], 1)
    tube = 2 * AROUND * ((len(v) - 2) // AROUND - 1)
    stripe = np.zeros(len(f), bool)
    stripe[:tube] = (np.arange(tube) // 2) % AROUND == AROUND // 4
    colors[stripe] = [0.1, 0.2, 0.6, 1.0]
    flip = flipped(v, f, ends) if ends else np.zeros(len(f), bool)
    colors[flip] = [0.9, 0.1, 0.1, 1.0]
    ax.add_collection3d(Poly3DCollection(v[f], facecolors=colors, edgecolors="none"))
    lo, hi = box
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo)
    ax.view_init(elev=65, azim=-90)
    ax.set_axis_off()
    ax.set_title(f"{title}\n{flip.sum()} flipped against both" if ends else title, fontsize=9)


def main():
    out, dirs = sys.argv[1], [Path(d) for d in sys.argv[2:]]
    cases = sorted({p.name.rsplit("-", 1)[0] for p in dirs[0].glob("*-rest.obj")})
    rows, cols = len(cases) * len(dirs), 4
    fig = plt.figure(figsize=(3.6 * cols, 3.0 * rows))
    for k, case in enumerate(cases):
        rest, f = read_obj(dirs[0] / f"{case}-rest.obj")
        curled, _ = read_obj(dirs[0] / f"{case}-curled.obj")
        grid = []
        for d in dirs:
            panels = [(f"{case}, {d.name}: curled", curled, None)]
            for what in ["linear", "predictor", "solve"]:
                v, _ = read_obj(d / f"{case}-{what}.obj")
                panels.append((f"{d.name}: {what} at ½", v, [rest, curled]))
            grid.append(panels)
        allv = np.concatenate([p[1] for panels in grid for p in panels])
        lo, hi = allv.min(0), allv.max(0)
        for i, panels in enumerate(grid):
            r = k * len(dirs) + i
            for c, (title, v, ends) in enumerate(panels):
                ax = fig.add_subplot(rows, cols, r * cols + c + 1, projection="3d")
                draw(ax, v, f, ends, title, (lo, hi))
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
