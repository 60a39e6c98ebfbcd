"""Renders one reference OBJ and other OBJs of the same mesh side by side, each coloured by
its per-vertex distance from the reference as a fraction of the reference's bounding-box
diagonal (white 0, red at `--scale`, default 1e-3: the interactive mode's bound, issue 38).
Two views per shape (front and side). Used to look at interactive against full solves:

    python3 tools/render_compare.py OUT.png "TITLE" REF.obj "label A" A.obj ["label B" B.obj ...]

Each shape is framed by the reference's bounding box, so the panels line up. Meshes are taken
as y-up (as OBJ exporters write them); `--zup` keeps z up.
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_obj(path):
    v, f = [], []
    for line in Path(path).read_text().splitlines():
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            v.append([float(x) for x in p[1:4]])
        elif p[0] == "f":
            idx = [int(q.split("/")[0]) - 1 for q in p[1:]]
            for k in range(1, len(idx) - 1):
                f.append([idx[0], idx[k], idx[k + 1]])
    return np.array(v), np.array(f)


def draw(ax, v, f, colour, lo, hi, elev, azim):
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-300
    e, a = np.radians(elev), np.radians(azim)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    light = 0.35 + 0.65 * np.abs(n @ view)
    faces = colour[f].mean(axis=1) * light[:, None]
    ax.add_collection3d(
        Poly3DCollection(tri, facecolors=np.clip(faces, 0, 1), edgecolors="none")
    )
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    for set_lim, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
        set_lim(c - half, c + half)
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()


def main():
    args = sys.argv[1:]
    scale = 1e-3
    zup = "--zup" in args
    args = [a for a in args if a != "--zup"]
    if "--scale" in args:
        k = args.index("--scale")
        scale = float(args[k + 1])
        del args[k : k + 2]
    out, title, ref = args[0], args[1], args[2]
    pairs = list(zip(args[3::2], args[4::2]))
    v0, f = read_obj(ref)
    # y-up to the plot's z-up: (x, y, z) -> (x, -z, y), front towards the viewer.
    up = (lambda v: v) if zup else (lambda v: v[:, [0, 2, 1]] * np.array([1.0, -1.0, 1.0]))
    v0 = up(v0)
    lo, hi = v0.min(axis=0), v0.max(axis=0)
    diag = np.linalg.norm(hi - lo)
    shapes = [("reference (full solve)", v0)] + [(lab, up(read_obj(p)[0])) for lab, p in pairs]
    fig = plt.figure(figsize=(4 * len(shapes), 8))
    for col, (label, v) in enumerate(shapes):
        d = np.linalg.norm(v - v0, axis=1) / diag
        t = np.clip(d / scale, 0, 1)[:, None]
        colour = (1 - t) * np.array([0.85, 0.85, 0.85]) + t * np.array([0.9, 0.05, 0.05])
        for row, (elev, azim) in enumerate([(10, -90), (10, 0 if zup else -20)]):
            ax = fig.add_subplot(2, len(shapes), row * len(shapes) + col + 1, projection="3d")
            draw(ax, v, f, colour, lo, hi, elev, azim)
            if row == 0:
                ax.set_title(f"{label}\nmax {d.max() * 100:.3f} % of diag", fontsize=9)
    fig.suptitle(f"{title} (red: ≥ {scale:g} of the diagonal from the reference)")
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main()
