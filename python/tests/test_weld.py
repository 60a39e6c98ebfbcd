"""Welded solves (issue 37): PhysicalBlend and SceneBlend treat vertices split at seams and hard
edges as one vertex and answer in the caller's layout, equal to the unsplit mesh."""

import numpy as np
import pytest

import morphkit
from conftest import bend, diag, tube


def split(shapes, F, shuffle):
    """Splits shapes of one connectivity as an exporter does at a seam: faces whose base
    centroid has y > 0 use copies of the vertices they share with the others. Returns the
    split shapes, faces and the unsplit vertex of each split vertex."""
    V0 = shapes[0]
    upper = V0[F].mean(axis=1)[:, 1] > 0
    n = len(V0)
    a = np.zeros(n, bool)
    b = np.zeros(n, bool)
    a[F[upper].ravel()] = True
    b[F[~upper].ravel()] = True
    seam = np.flatnonzero(a & b)
    assert len(seam) > 10
    copy = np.full(n, -1)
    copy[seam] = n + np.arange(len(seam))
    origin = np.concatenate([np.arange(n), seam])
    G = F.copy()
    up = G[upper]
    G[upper] = np.where(copy[up] >= 0, copy[up], up)
    order = np.arange(len(origin))
    if shuffle:
        order = np.random.default_rng(7).permutation(len(origin))
    new_index = np.empty_like(order)
    new_index[order] = np.arange(len(order))
    G = new_index[G]
    out = [S[origin][order] for S in shapes]
    return out, G, origin[order]


@pytest.fixture(scope="module")
def rig():
    V, F = tube()
    return V, bend(V, 2.0), F


@pytest.mark.parametrize("shuffle", [False, True])
def test_a_split_rig_solves_as_the_unsplit_one(rig, shuffle):
    V, B, F = rig
    # Tight, so that the solves of two vertex orders agree to round-off.
    want = morphkit.PhysicalBlend(V, [B], F, gradient_tolerance=1e-10).solve(0.5)
    (SV, SB), G, origin = split([V, B], F, shuffle)
    b = morphkit.PhysicalBlend(SV, [SB], G, gradient_tolerance=1e-10)
    copies = len(origin) - len(V)
    assert b.welded_vertices == copies
    assert b.summary["welded_vertices"] == copies
    got = b.solve(0.5)
    assert got.shape == SV.shape
    err = np.linalg.norm(got - want[origin], axis=1).max() / diag(V)
    if shuffle:
        assert err < 1e-9, err
    else:
        assert err == 0.0, "copies after their originals weld to the very same mesh"
    many = b.solve_many([0.5, 0.25])
    assert np.array_equal(many[0], got)
    assert np.abs(b.predict(0.5) - b.predictor().predict(0.5)).max() == 0.0
    # Unwelded, the seam tears: the result differs.
    torn = morphkit.PhysicalBlend(SV, [SB], G, weld=False)
    assert torn.welded_vertices == 0


def test_fixed_and_pulled_ids_are_the_callers(rig):
    V, B, F = rig
    fixed = list(range(12))
    pulled = 24 * 12 + 3  # a vertex of the last ring
    target = B[pulled] + np.array([0.0, 0.0, 0.2])
    want = morphkit.PhysicalBlend(V, [B], F, fixed=fixed, gradient_tolerance=1e-10).solve(
        0.5, pulls={pulled: target}
    )
    (SV, SB), G, origin = split([V, B], F, True)
    # Each unsplit vertex by its last split vertex (a copy where there is one).
    last = {int(o): k for k, o in enumerate(origin)}
    b = morphkit.PhysicalBlend(
        SV, [SB], G, fixed=[last[v] for v in fixed], gradient_tolerance=1e-10
    )
    got = b.solve(0.5, pulls={last[pulled]: target})
    err = np.linalg.norm(got - want[origin], axis=1).max() / diag(V)
    assert err < 1e-9, err


def test_vertices_that_part_in_a_target_are_not_welded(rig):
    V, B, F = rig
    (SV, SB), G, origin = split([V, B], F, False)
    SB = SB.copy()
    SB[len(V):, 2] += 0.05
    assert morphkit.PhysicalBlend(SV, [SB], G).welded_vertices == 0


def test_nothing_to_weld_is_bit_identical(rig):
    V, B, F = rig
    a = morphkit.PhysicalBlend(V, [B], F)
    assert a.welded_vertices == 0
    assert np.array_equal(a.solve(0.5), morphkit.PhysicalBlend(V, [B], F, weld=False).solve(0.5))


def test_a_split_scene_solves_as_the_unsplit_one(rig):
    V, B, F = rig
    pulled = 24 * 12 + 3
    keys = [(0.0, tuple(B[pulled])), (1.0, tuple(B[pulled] + [0.0, 0.0, 0.2]))]
    fixed = list(range(12))
    want = morphkit.SceneBlend(V, [B], F, pulls=[(pulled, keys)], fixed=fixed).solve(0.5, frame=1.0)
    (SV, SB), G, origin = split([V, B], F, True)
    last = {int(o): k for k, o in enumerate(origin)}
    s = morphkit.SceneBlend(
        SV, [SB], G, pulls=[(last[pulled], keys)], fixed=[last[v] for v in fixed]
    )
    got = s.solve(0.5, frame=1.0)
    err = np.linalg.norm(got - want[origin], axis=1).max() / diag(V)
    assert err < 1e-9, err


def test_a_split_target_transfers_as_the_unsplit_one():
    VS, FS = tube()
    VT, FT = tube(rings=30, around=16, radius=0.7)
    markers = [[r * 12 + k, (r * 30 // 24) * 16 + k * 4 // 3] for r in (0, 12, 24) for k in (0, 3, 6, 9)]
    frames = np.stack([bend(VS, a) for a in (0.5, 1.2)])
    c = morphkit.Correspondence.from_markers(VS, FS, VT, FT, markers)
    want = morphkit.Transfer(VS, FS, VT, FT, c).transfer_many(frames)
    (SVT,), SFT, origin = split([VT], FT, True)
    last = {int(o): k for k, o in enumerate(origin)}
    sm = [[s, last[t]] for s, t in markers]
    sc = morphkit.Correspondence.from_markers(VS, FS, SVT, SFT, sm)
    assert sc.matches == c.matches, "triangles keep their ids"
    got = morphkit.Transfer(VS, FS, SVT, SFT, sc).transfer_many(frames)
    assert got.shape == (2, len(SVT), 3)
    err = np.linalg.norm(got - want[:, origin], axis=2).max() / diag(VT)
    assert err < 1e-9, err
    rig = morphkit.RigTransfer(VS, FS, SVT, SFT, sc).transfer_many(frames)
    rig_want = morphkit.RigTransfer(VS, FS, VT, FT, c).transfer_many(frames)
    assert np.linalg.norm(rig - rig_want[:, origin], axis=2).max() / diag(VT) < 1e-9
