"""Synthesis: flexibility, partitions and intelligent scribbling, Eq. 5 weights, geodesics and
recipes (equal to `morphkit synth`)."""

import json

import numpy as np
import pytest

import morphkit
from conftest import diag, grid, tube


def joint(V, angle, at=3.0):
    """Rotates the part x > at about the z axis through (at, 0, 0): a hinge joint."""
    out = V.copy()
    c, s = np.cos(angle), np.sin(angle)
    right = V[:, 0] > at
    d = V[right] - [at, 0, 0]
    out[right, 0] = at + c * d[:, 0] - s * d[:, 1]
    out[right, 1] = s * d[:, 0] + c * d[:, 1]
    return out


def centroids_x(V, F):
    return V[F].mean(axis=1)[:, 0]


@pytest.fixture(scope="module")
def jointed():
    V, F = tube(rings=24, around=10)
    frames = np.stack([joint(V, a) for a in (0.3, 0.6, 0.9)])
    return V, F, frames


def test_flexibility_is_at_the_joint(jointed):
    V, F, frames = jointed
    flex = morphkit.flexibility(V, F, frames)
    assert flex.shape == (len(F),) and (flex >= 0).all()
    x = centroids_x(V, F)
    near = np.abs(x - 3.0) < 0.5
    far = np.abs(x - 3.0) > 1.0
    assert flex[far].max() < 1e-9 * flex.max()
    assert flex[near].max() == flex.max()
    rigid = np.stack([V + [1.0, 2.0, 3.0], V @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]).T])
    assert morphkit.flexibility(V, F, rigid).max() < 1e-9


def test_scribble_selects_the_stiff_half_and_weights_blend(jointed):
    V, F, frames = jointed
    flex = morphkit.flexibility(V, F, frames)
    parts = morphkit.Partitions(V, F, flex)
    x = centroids_x(V, F)
    assert parts.labels.shape == (len(F),) and parts.num_partitions >= 2
    assert parts.stiff[x < 2.0].all() and parts.stiff[x > 4.0].all()
    # A sloppy scribble over most of the right half selects the whole right stiff part.
    scribbled = np.flatnonzero((x > 3.8) & (x < 5.6)).tolist()
    sel = parts.refine(triangles=scribbled)
    assert sel[x > 4.0].all() and not sel[x < 2.0].any()
    w = parts.blend_weights(sel)
    assert np.allclose(w[x > 4.0], 1.0) and np.allclose(w[x < 2.0], 0.0)
    assert ((w >= 0) & (w <= 1)).all()
    with pytest.raises(morphkit.TransferError):
        parts.refine()
    with pytest.raises(morphkit.MeshError):
        parts.blend_weights(sel[:-1])


def test_geodesic_distance_on_a_plane_is_euclidean():
    V, F = grid(20)
    d = morphkit.geodesic_distance(V, F, [0])
    e = np.linalg.norm(V - V[0], axis=1)
    far = e > 5
    assert np.abs(d[far] / e[far] - 1).max() < 0.05
    assert d[0] == pytest.approx(0.0, abs=1e-9)


def test_recipe_equals_the_cli(tmp_path, cli, jointed):
    V, F, frames = jointed
    morphkit.write(tmp_path / "tube.obj", V, F)
    morphkit.write_animation(tmp_path / "frames", frames, F)
    x = centroids_x(V, F)
    (tmp_path / "far.json").write_text(
        json.dumps({"triangles": np.flatnonzero(x > 3.5).tolist()})
    )
    (tmp_path / "recipe.toml").write_text(
        'target = "tube.obj"\nframes = 3\n[[layer]]\nsource_frames = "frames"\n'
        'scribble = "far.json"\n'
    )
    ours, F2 = morphkit.synthesize(tmp_path / "recipe.toml")
    assert ours.shape == frames.shape
    np.testing.assert_array_equal(F2, F)
    # The scribbled right half bends as in the source frames; the left half keeps its
    # reference shape: edge lengths there are unchanged, and the right end moves.
    left = np.flatnonzero(V[:, 0] < 2.0)
    for f in ours:
        d0 = np.linalg.norm(V[left][:, None] - V[left][None], axis=2)
        d1 = np.linalg.norm(f[left][:, None] - f[left][None], axis=2)
        assert np.abs(d1 - d0).max() < 0.01 * diag(V)  # the blend band starts near x = 2
    tip = V[:, 0] == V[:, 0].max()
    assert np.linalg.norm(ours[-1][tip] - V[tip], axis=1).min() > 0.1 * diag(V)
    cli("synth", tmp_path / "recipe.toml", "--out", tmp_path / "out")
    theirs, _, _ = morphkit.read_animation(tmp_path / "out")
    assert np.abs(ours - theirs).max() <= 1e-9 * diag(V)
    (tmp_path / "bad.toml").write_text('target = "nope.obj"\n')
    with pytest.raises(morphkit.FileError, match="bad.toml"):
        morphkit.synthesize(tmp_path / "bad.toml")


def test_geodesic_distance_matches_libigl_exact():
    igl = pytest.importorskip("igl")
    V, F = tube(rings=30, around=16)
    d = morphkit.geodesic_distance(V, F, [0])
    exact = igl.exact_geodesic(
        V, F.astype(np.int64), np.array([0]), np.array([], dtype=np.int64),
        np.arange(len(V)), np.array([], dtype=np.int64),
    )
    far = exact > 0.25 * exact.max()
    # The heat method (Crane et al. 2013) at the default time step is within a few percent.
    assert np.abs(d[far] / exact[far] - 1).max() < 0.15  # measured 0.090, mean 0.0096
    assert np.abs(d[far] / exact[far] - 1).mean() < 0.03


def test_edit_pose_turns_the_selected_part_about_its_joint(jointed):
    V, F, frames = jointed
    parts = morphkit.Partitions(V, F, morphkit.flexibility(V, F, frames))
    x = centroids_x(V, F)
    sel = parts.refine(triangles=np.flatnonzero(x > 4.0).tolist())
    X = parts.edit_pose(sel, (0.0, 0.0, 1.0), 0.6)
    left = V[:, 0] < 2.0
    right = V[:, 0] > 4.5
    assert np.abs(X[left] - V[left]).max() < 0.01 * diag(V)  # the rest stays put
    # The right part is turned rigidly by 0.6 rad about z: compare edge directions.
    a, b = np.flatnonzero(right)[[0, -1]]
    d0, d1 = V[b] - V[a], X[b] - X[a]
    ang = np.arctan2(d1[1], d1[0]) - np.arctan2(d0[1], d0[0])
    assert abs(ang - 0.6) < 0.05
    with pytest.raises(morphkit.TransferError):
        parts.edit_pose(sel, (0.0, 0.0, 0.0), 0.6)


def test_partitions_refuse_bad_flexibility(jointed):
    # One finite value ≥ 0 per triangle; a wrong length used to panic in the library (index out
    # of bounds) and NaN was taken for flexible.
    V, F, frames = jointed
    flex = morphkit.flexibility(V, F, frames)
    nf = len(F)
    for bad in (flex[:-1], np.append(flex, 0.0), flex[:10]):
        with pytest.raises(
            morphkit.MeshError,
            match=rf"flexibility: has {len(bad)} entries, expected {nf} \(one per triangle of F\)",
        ):
            morphkit.Partitions(V, F, bad)
    for value, shown in ((np.nan, "NaN"), (np.inf, "inf"), (-0.5, "-0.5")):
        bad = flex.copy()
        bad[7] = value
        bad[9] = value
        with pytest.raises(
            morphkit.MeshError, match=rf"flexibility\[7\] = {shown} is not a finite number ≥ 0"
        ):
            morphkit.Partitions(V, F, bad)
    with pytest.raises(morphkit.MeshError, match="flexibility"):
        morphkit.Partitions(V, F, "stiff")
    with pytest.raises(morphkit.MeshError, match="flexibility"):
        morphkit.Partitions(V, F, np.stack([flex, flex], axis=1))
    # A list, float32 and an integer array are numbers too.
    parts = morphkit.Partitions(V, F, flex)
    for same in (flex.tolist(), flex.astype(np.float32), (flex > 0.5 * flex.max()).astype(int)):
        other = morphkit.Partitions(V, F, same)
        assert other.labels.shape == (nf,)
    assert np.array_equal(morphkit.Partitions(V, F, flex.tolist()).labels, parts.labels)
