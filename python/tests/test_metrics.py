"""Quality metrics on any V, F, with libigl cross-checks where it computes the same thing."""

import numpy as np
import pytest

import morphkit
from conftest import bend, grid, tube


def closed_box():
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    F = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )
    return V, F


def test_identity_has_no_strain():
    V, F = tube()
    m = morphkit.metrics(V, V, F)
    assert m["edge_length_rms"] == 0 and m["edge_length_max"] == 0 and m["area_rms"] == 0
    assert m["folds"] == 0 and m["volume"] is None


def test_uniform_scale():
    V, F = closed_box()
    assert morphkit.metrics(V, V, F)["volume"] == pytest.approx(1.0)
    m = morphkit.metrics(V, 1.5 * V, F)
    assert m["edge_length_rms"] == pytest.approx(0.5)
    assert m["area_rms"] == pytest.approx(1.25)
    assert m["volume_ratio"] == pytest.approx(1.5**3)


def test_folds_counted():
    V, F = grid(3)
    X = V.copy()
    X[:, 2] = 0.0
    X[:, 0] = -X[:, 0]  # mirrored: every normal flips
    assert morphkit.metrics(V, X, F)["folds"] == len(F)


def test_area_strain_matches_libigl():
    igl = pytest.importorskip("igl")
    V, F = tube()
    rng = np.random.default_rng(7)
    X = V + 0.02 * rng.standard_normal(V.shape)
    a0 = igl.doublearea(V, F) / 2
    a1 = igl.doublearea(X, F) / 2
    expected = float(np.sqrt(np.mean((a1 / a0 - 1) ** 2)))
    assert morphkit.metrics(V, X, F)["area_rms"] == pytest.approx(expected, rel=1e-9)


def test_continuity_of_a_physical_sequence():
    """A bent tube's 24 frames move smoothly: no jump, and its fastest vertex moves at least as
    fast as the linear blend's (an arc is longer than its chord)."""
    from conftest import bend

    V, F = tube()
    B = bend(V, 2.0)
    b = morphkit.PhysicalBlend(V, [B], F)
    alphas = np.linspace(0.0, 1.0, 24)
    frames = b.solve_many([[a] for a in alphas], threads=2)
    linear = [(1 - a) * V + a * B for a in alphas]
    c = morphkit.continuity(frames, linear)
    assert c["bound"] == 4.0 and c["jumps"] == []
    assert 1.0 <= c["worst_ratio"] < 4.0, c["worst_ratio"]
    assert c["worst_frames"][1] == c["worst_frames"][0] + 1


def test_continuity_finds_a_part_that_snaps():
    V = np.array([[float(i), 0.0, 0.0] for i in range(10)])
    linear = np.stack([V + [0.1 * k, 0, 0] for k in range(6)])
    frames = linear.copy()
    frames[3:, [3, 4], 1] += 1.0  # two vertices swing out between frames 2 and 3
    c = morphkit.continuity(frames, linear)
    assert len(c["jumps"]) == 1
    j = c["jumps"][0]
    assert j["frames"] == [2, 3] and j["vertices"] == [3, 4] and j["vertex"] in (3, 4)
    assert j["ratio"] == pytest.approx(np.hypot(1.0, 0.1) / 0.1)
    assert morphkit.continuity(frames, linear, bound=20.0)["jumps"] == []
    with pytest.raises(morphkit.MeshError, match="frames"):
        morphkit.continuity(frames[:4], linear)
    with pytest.raises(morphkit.MeshError, match="vertices"):
        morphkit.continuity(frames[:, :5], linear)
    ragged = list(frames)
    ragged[2] = ragged[2][:5]
    with pytest.raises(morphkit.MeshError, match="frame 2"):
        morphkit.continuity(ragged, linear)
    with pytest.raises(morphkit.MorphkitError, match="bound"):
        morphkit.continuity(frames, linear, bound=-1.0)
