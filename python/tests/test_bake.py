"""PhysicalBlend.bake (issue 56): in-between and combination shapes that a DCC plays as
ordinary blendshapes; BakedRig.evaluate is what such a client computes."""

import numpy as np
import pytest

import morphkit
from conftest import bend, diag, tube


def split_rig():
    """A tube split along one seam line (its copies coincide in every shape, so the blend
    welds them), bent about z and about y, and a third target that twists its far end."""
    V, F = tube(rings=16, around=10)
    n_around = 10
    # Split: every vertex at k == 0 gets a copy used by the triangles of the last column.
    seam = [r * n_around for r in range(17)]
    copy = {v: len(V) + i for i, v in enumerate(seam)}
    V = np.vstack([V, V[seam]])
    F = F.copy()
    for t in F:
        if any(v % n_around == n_around - 1 for v in t):
            for c in range(3):
                if t[c] in copy:
                    t[c] = copy[t[c]]
    Bz = bend(V, np.pi / 2)
    By = bend(V[:, [0, 2, 1]], np.pi / 2)[:, [0, 2, 1]]
    s = np.clip((V[:, 0] - 3.0) / 3.0, 0, 1) * np.radians(60)
    Tw = V.copy()
    Tw[:, 1] = V[:, 1] * np.cos(s) - V[:, 2] * np.sin(s)
    Tw[:, 2] = V[:, 1] * np.sin(s) + V[:, 2] * np.cos(s)
    return V, [Bz, By, Tw], F


def test_a_bake_plays_the_solve_at_its_samples_and_the_shapes_exactly():
    V, T, F = split_rig()
    blend = morphkit.PhysicalBlend(V, T, F)
    assert blend.welded_vertices == 17
    rig = blend.bake(inbetweens=3, threads=2, inbetween_tolerance=0.0)
    assert isinstance(rig, morphkit.BakedRig)
    assert rig.inbetween_weights == [[0.25, 0.5, 0.75, 1.0]] * 3
    assert rig.combinations == [(0, 1), (0, 2), (1, 2)]
    assert rig.num_shapes == 12 + 3 * 2
    assert rig.combination_levels == [[1.0, 4.0]] * 3
    assert rig.damping == 0.0
    d = diag(V)
    np.testing.assert_array_equal(rig.base, V)
    # One-hot weights: every input vertex (seam copies included) is its own target: the stored
    # shape is the target's own displacement, bit for bit, and base + it is the target up to
    # the rounding of that sum (what every client computes).
    for t in range(3):
        w = [0.0] * 3
        w[t] = 1.0
        np.testing.assert_array_equal(rig.inbetween(t, 3), T[t] - V)
        assert np.abs(rig.evaluate(w) - T[t]).max() <= 1e-15 * d
        for a in (0.25, 0.5, 0.75):
            w[t] = a
            assert np.abs(rig.evaluate(w) - blend.solve(w)).max() <= 1e-12 * d
    for k, (i, j) in enumerate(rig.combinations):
        for s, level in ((0.5, 1.0), (1.0, 4.0)):
            w = [0.0] * 3
            w[i] = w[j] = s
            assert rig.combination_weights(w)[k] == level
            assert np.abs(rig.evaluate(w) - blend.solve(w)).max() <= 1e-12 * d
    # Three on: the plain product by default; damped by the square of the pair's share of
    # the total weight when asked.
    np.testing.assert_allclose(rig.combination_weights([0.5, 0.5, 0.5]), [1.0] * 3, rtol=1e-15)
    damped = blend.bake(inbetweens=3, damping=2.0)
    np.testing.assert_allclose(damped.combination_weights([0.5, 0.5, 0.5]), [4.0 / 9.0] * 3, rtol=1e-15)
    with pytest.raises(IndexError):
        rig.inbetween(3, 0)
    with pytest.raises(morphkit.MorphkitError):
        rig.evaluate([0.5, 0.5])


def test_a_bake_is_closer_to_the_solve_than_the_linear_blend_between_its_samples():
    V, T, F = split_rig()
    blend = morphkit.PhysicalBlend(V, T, F)
    rig = blend.bake()
    lin = lambda w: V + sum(wi * (Ti - V) for wi, Ti in zip(w, T))
    for w in ([0.3, 0, 0], [0, 0.62, 0], [0.7, 0.4, 0], [0.6, 0.5, 0.7]):
        solved = blend.solve(w)
        baked = np.linalg.norm(rig.evaluate(w) - solved, axis=1).max()
        linear = np.linalg.norm(lin(w) - solved, axis=1).max()
        assert baked < linear, (w, baked, linear)


def test_a_bake_adds_in_betweens_where_the_tolerance_needs_them():
    # The 90° bends are not piecewise linear at the quarters: halving segments where the
    # solve is farther than the tolerance adds in-betweens (at dyadic weights, each the solve
    # there), within max_refined, and brings the bake closer to the solve between them.
    V, T, F = split_rig()
    blend = morphkit.PhysicalBlend(V, T, F)
    regular = blend.bake(inbetweens=3, inbetween_tolerance=0.0, max_pairs=0)
    refined = blend.bake(inbetweens=3, inbetween_tolerance=1e-3, max_pairs=0)
    counts = [len(w) for w in refined.inbetween_weights]
    assert sum(counts) > 12
    d = diag(V)
    worst = [0.0, 0.0]
    for t in range(3):
        for a in refined.inbetween_weights[t]:
            assert (a * 32) % 1 == 0
        for a in np.linspace(0.05, 0.95, 19):
            w = [0.0] * 3
            w[t] = a
            solved = blend.solve(w)
            for i, rig in enumerate((regular, refined)):
                worst[i] = max(worst[i], np.abs(rig.evaluate(w) - solved).max() / d)
    assert worst[1] < worst[0]
    capped = blend.bake(inbetweens=3, inbetween_tolerance=1e-3, max_pairs=0, max_refined=1)
    assert capped.num_shapes == regular.num_shapes + 1
