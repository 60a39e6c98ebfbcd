"""PhysicalBlend's interactive mode (issue 38): solve(..., interactive=True) after one
preparation, its error estimate in last_stats, refinement, and the preparation's cache file."""

import numpy as np
import pytest

import morphkit
from conftest import bend, diag, tube


@pytest.fixture(scope="module")
def rig():
    V, F = tube(rings=24, around=10)
    bulge = V.copy()
    s = 1.0 + 0.3 * np.sin(np.pi * V[:, 0] / V[:, 0].max())
    bulge[:, 1] *= s
    bulge[:, 2] *= s
    return V, [bend(V, 1.5), bulge], F


def dist(a, b):
    return np.linalg.norm(a - b, axis=1).max()


def test_close_to_the_full_solve_within_its_estimate(rig):
    V, T, F = rig
    b = morphkit.PhysicalBlend(V, T, F)
    info = b.prepare_interactive(threads=2)
    assert info["snapshots"] == 16 and info["unconverged"] == 0 and not info["loaded"]
    d = diag(V)
    for w in ([0.4, 0.3], [0.7, 0.0], [0.2, 0.6]):
        full = b.solve(w)
        assert b.last_stats["error_estimate"] is None
        fast = b.solve(w, interactive=True)
        stats = b.last_stats
        error = dist(fast, full) / d
        assert error <= stats["error_estimate"], (w, error, stats)
        assert error < 0.5 * dist(b.predict(w), full) / d, w
        refined = b.solve(w, interactive=True, refine=1)
        assert dist(refined, full) / d <= max(error, 1e-5), w
    # One-hot weights: the target itself, exactly, with a zero estimate.
    one = b.solve([1.0, 0.0], interactive=True)
    assert b.last_stats["error_estimate"] == 0.0
    assert np.array_equal(one, b.solve([1.0, 0.0]))


def test_the_cache_file_gives_the_same_shapes(rig, tmp_path):
    V, T, F = rig
    path = tmp_path / "rig.mkinteractive"
    a = morphkit.PhysicalBlend(V, T, F)
    first = a.prepare_interactive(cache=path)
    assert not first["loaded"] and first["replaced"] is None and path.is_file()
    b = morphkit.PhysicalBlend(V, T, F)
    again = b.prepare_interactive(cache=str(path))
    assert again["loaded"] and again["snapshots"] == first["snapshots"]
    w = [0.45, 0.35]
    assert np.array_equal(a.solve(w, interactive=True), b.solve(w, interactive=True))
    # Another rig's preparation is replaced, not used.
    c = morphkit.PhysicalBlend(V, T, F, hinge_weight=0.02)
    other = c.prepare_interactive(cache=path)
    assert not other["loaded"] and "another rig" in other["replaced"]
    assert not list(tmp_path.glob(".*.tmp"))


def test_bad_calls_are_clear(rig):
    V, T, F = rig
    b = morphkit.PhysicalBlend(V, T, F)
    with pytest.raises(morphkit.BlendError, match="pulls"):
        b.solve([0.5, 0.0], interactive=True, pulls={0: (0.0, 0.0, 0.0)})
    with pytest.raises(morphkit.BlendError, match="refine"):
        b.solve([0.5, 0.0], interactive=True, refine=-1)
    with pytest.raises(morphkit.BlendError, match="threads"):
        b.prepare_interactive(threads=0)
