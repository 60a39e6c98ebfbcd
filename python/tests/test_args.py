"""Integer arguments: counts and options (threads, max_newton_iterations, …) and indices
(geodesic sources, fixed vertices, pulls, scribbles, markers) read in one way: a negative or
huge value is the module's error naming the argument and its range, never a bare
OverflowError; a non-integer is a TypeError naming the argument."""

import numpy as np
import pytest

import morphkit
from conftest import bend, grid, tube


@pytest.fixture(scope="module")
def rig():
    V, F = tube(8, 8)
    return V, bend(V, 1.0), F


@pytest.fixture(scope="module")
def blend(rig):
    V, B, F = rig
    return morphkit.PhysicalBlend(V, [B], F)


@pytest.mark.parametrize("value", [-1, 0, -(10**30)])
def test_threads_below_one(blend, value):
    with pytest.raises(morphkit.BlendError, match=rf"threads: must be an integer ≥ 1, got {value}$"):
        blend.solve_many([[0.5]], threads=value)


def test_threads_huge_and_not_an_integer(blend):
    # Python's integers are unbounded: more threads than fit in 64 bits are "as many as there
    # are frames", as any count above the number of frames.
    one = blend.solve_many([[0.3], [0.6]], threads=1)
    assert np.array_equal(blend.solve_many([[0.3], [0.6]], threads=10**30), one)
    with pytest.raises(TypeError, match="threads: expected an integer, got float"):
        blend.solve_many([[0.5]], threads=1.5)
    with pytest.raises(TypeError, match="threads: expected an integer, got str"):
        blend.solve_many([[0.5]], threads="2")
    # numpy integers are integers; the default is one thread.
    assert np.array_equal(blend.solve_many([[0.3], [0.6]], threads=np.int64(2)), one)
    assert np.array_equal(blend.solve_many([[0.3], [0.6]]), one)


def test_blend_options(rig):
    V, B, F = rig
    with pytest.raises(
        morphkit.BlendError, match=r"max_newton_iterations: must be an integer ≥ 0, got -1$"
    ):
        morphkit.PhysicalBlend(V, [B], F, max_newton_iterations=-1)
    with pytest.raises(morphkit.BlendError, match=r"thin_band_rings: must be an integer ≥ 0, got -3$"):
        morphkit.PhysicalBlend(V, [B], F, thin_band_rings=-3)
    with pytest.raises(TypeError, match="max_newton_iterations: expected an integer"):
        morphkit.PhysicalBlend(V, [B], F, max_newton_iterations=2.5)
    b = morphkit.PhysicalBlend(V, [B], F, max_newton_iterations=np.uint16(5), thin_band_rings=0)
    assert b.solve(0.3).shape == V.shape


def test_scene_options(rig):
    V, B, F = rig
    with pytest.raises(morphkit.BlendError, match=r"max_rounds: must be an integer ≥ 0, got -1$"):
        morphkit.SceneBlend(V, [B], F, max_rounds=-1)
    scene = morphkit.SceneBlend(V, [B], F, max_rounds=0)
    with pytest.raises(morphkit.BlendError, match=r"threads: must be an integer ≥ 1, got -1$"):
        scene.solve_many([0.5], threads=-1)
    assert morphkit.SceneBlend(V, [B], F).solve_many([0.5]).shape == (1, len(V), 3)


def test_geodesic_sources(rig):
    V, _, F = rig
    n = len(V)
    with pytest.raises(
        morphkit.TransferError,
        match=rf"^sources\[0\] = 10000000 is not a vertex index \(mesh has {n} vertices\)$",
    ):
        morphkit.geodesic_distance(V, F, [10**7])
    with pytest.raises(
        morphkit.TransferError, match=rf"^sources\[2\] = -1 is not a vertex index \(mesh has {n} vertices\)$"
    ):
        morphkit.geodesic_distance(V, F, [0, 1, -1])
    with pytest.raises(morphkit.TransferError, match=rf"sources\[1\] = {10**30} is not a vertex index"):
        morphkit.geodesic_distance(V, F, [0, 10**30])
    with pytest.raises(morphkit.TransferError, match=rf"sources\[0\] = {n} is not a vertex index"):
        morphkit.geodesic_distance(V, F, np.array([n]))
    with pytest.raises(TypeError, match=r"sources\[0\]: expected an integer, got float"):
        morphkit.geodesic_distance(V, F, [0.5])
    with pytest.raises(TypeError, match="sources: expected a sequence of vertex indices, got int"):
        morphkit.geodesic_distance(V, F, 3)
    d = morphkit.geodesic_distance(V, F, np.array([0, n - 1], dtype=np.uint16))
    assert np.array_equal(d, morphkit.geodesic_distance(V, F, [0, n - 1]))


def test_fixed_and_pulls(rig):
    V, B, F = rig
    n = len(V)
    with pytest.raises(
        morphkit.BlendError, match=rf"^fixed\[1\] = -1 is not a vertex index \(mesh has {n} vertices\)$"
    ):
        morphkit.PhysicalBlend(V, [B], F, fixed=[0, -1])
    with pytest.raises(morphkit.BlendError, match=rf"^fixed\[0\] = {n} is not a vertex index"):
        morphkit.SceneBlend(V, [B], F, fixed=np.array([n]))
    with pytest.raises(
        morphkit.BlendError, match=rf"^pulls\[0\]\[0\] = -1 is not a vertex index \(mesh has {n} vertices\)$"
    ):
        morphkit.SceneBlend(V, [B], F, pulls=[(-1, [(0.0, (0, 0, 0))])])
    with pytest.raises(morphkit.BlendError, match=rf"^pulls\[1\]\[0\] = {10**7} is not a vertex index"):
        morphkit.SceneBlend(
            V, [B], F, pulls=[(0, [(0.0, (0, 0, 0))]), (10**7, [(0.0, (0, 0, 0))])]
        )
    G, FG = grid(4)
    b = morphkit.PhysicalBlend(G, [G.copy()], FG, fixed=[i for i in range(len(G)) if G[i, 0] <= 1.0])
    with pytest.raises(morphkit.BlendError, match=r"^pulls vertex = -2 is not a vertex index \(mesh has 25 vertices\)$"):
        b.solve(0.0, pulls={-2: (0, 0, 0)})
    with pytest.raises(morphkit.BlendError, match=r"^pulls\[0\]\[0\] = 25 is not a vertex index"):
        b.solve(0.0, pulls=[(25, (0, 0, 0))])


def test_scribbles():
    V, F = tube(rings=12, around=8)
    parts = morphkit.Partitions(V, F, np.zeros(len(F)))
    with pytest.raises(
        morphkit.TransferError,
        match=rf"^triangles\[1\] = -1 is not a triangle index \(mesh has {len(F)} triangles\)$",
    ):
        parts.refine(triangles=[0, -1])
    with pytest.raises(
        morphkit.TransferError,
        match=rf"^vertices\[0\] = {len(V)} is not a vertex index \(mesh has {len(V)} vertices\)$",
    ):
        parts.refine(vertices=[len(V)])
    sel = parts.refine(triangles=np.arange(150, dtype=np.uint8))  # most of the one stiff part
    assert sel.shape == (len(F),) and sel.all()


def test_markers():
    V, F = tube(8, 8)
    W, G = tube(6, 6)
    pairs = [[k, k] for k in range(8)]
    with pytest.raises(
        morphkit.TransferError,
        match=rf"^markers\[3\]\[1\] = {len(W)} is not a vertex index \(mesh has {len(W)} vertices\)$",
    ):
        morphkit.Correspondence.from_markers(V, F, W, G, pairs[:3] + [[3, len(W)]] + pairs[4:])
    with pytest.raises(morphkit.TransferError, match=rf"^markers\[0\]\[0\] = {10**30} is not a vertex"):
        morphkit.Correspondence.from_markers(V, F, W, G, [[10**30, 0]] + pairs[1:])
