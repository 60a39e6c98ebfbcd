"""Correspondence and Transfer: self-transfer, persistence, and equality with the CLI."""

import json

import numpy as np
import pytest

import morphkit
from conftest import bend, diag, tube


def test_identity_self_transfer_is_exact():
    V, F = tube()
    c = morphkit.Correspondence.identity(V, F)
    t = morphkit.Transfer(V, F, V, F, c, combine="nearest", translation="fixed")
    frames = np.stack([bend(V, a) for a in (0.3, 0.9)])
    out = t.transfer_many(frames)
    assert out.shape == frames.shape
    # "fixed" keeps the constraint vertex where the reference has it; the bent tubes keep
    # vertex 0 (x = 0) in place, so the transfer reproduces them.
    assert np.abs(out - frames).max() < 1e-8 * diag(V)
    np.testing.assert_array_equal(t.transfer(frames[1]), out[1])


def test_match_confidence_is_one_onto_itself_and_low_inside_out():
    V, F = tube(8, 8)
    F = np.asarray(F)
    c = morphkit.Correspondence.identity(V, F)
    conf = c.match_confidence(V, F, V, F)
    assert conf.shape == (len(F),)
    assert np.abs(conf - 1.0).max() < 1e-12
    away = c.match_confidence(V, F, V, F[:, [0, 2, 1]], combine="mean")
    assert (away < 0.5).all()
    with pytest.raises(morphkit.TransferError):
        c.match_confidence(V, F, V[:10], F[:2])


def test_save_load_round_trip(tmp_path):
    V, F = tube(8, 8)
    c = morphkit.Correspondence.identity(V, F)
    c.save(tmp_path / "c.json")
    c2 = morphkit.Correspondence.load(tmp_path / "c.json")
    assert c2.matches == c.matches
    assert json.loads((tmp_path / "c.json").read_text())["identity"] is True
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(morphkit.FileError, match="bad.json"):
        morphkit.Correspondence.load(tmp_path / "bad.json")


def test_bad_markers_and_options():
    V, F = tube(8, 8)
    with pytest.raises(morphkit.TransferError):
        morphkit.Correspondence.from_markers(V, F, V, F, [[0, 0]])
    with pytest.raises(morphkit.TransferError, match=r"markers\[0\]\[0\] = -1 is not a vertex"):
        morphkit.Correspondence.from_markers(V, F, V, F, [[-1, 0]] * 8)
    with pytest.raises(morphkit.TransferError, match="out of range|vertex"):
        morphkit.Correspondence.from_markers(V, F, V, F, np.array([[k, k] for k in range(7)] + [[len(V), 0]]))
    c = morphkit.Correspondence.identity(V, F)
    with pytest.raises(morphkit.TransferError, match="combine"):
        morphkit.Transfer(V, F, V, F, c, combine="median")
    t = morphkit.Transfer(V, F, V, F, c)
    with pytest.raises(morphkit.MeshError, match="vertices"):
        t.transfer(V[:-1])


@pytest.fixture(scope="module")
def cat_dog():
    import os
    import pathlib

    root = os.environ.get("MORPHKIT_DATA")
    if not root:
        pytest.skip("MORPHKIT_DATA is not set")
    d = pathlib.Path(root) / "lowpoly-cat-dog"
    for f in ("cat-reference.obj", "dog-reference.obj", "markers-cat-dog.json"):
        if not (d / f).exists():
            raise FileNotFoundError(d / f)
    return d


def cat_dog_inputs(d):
    """The cat and dog references and the cat's run frames."""
    VS, FS = morphkit.read(d / "cat-reference.obj")
    VT, FT = morphkit.read(d / "dog-reference.obj")
    frames, _, _ = morphkit.read_animation(d / "cat-run")
    return VS, FS, VT, FT, frames


def cli_transfer(cli, d, out, *flags):
    """`morphkit transfer` of the cat's run onto the dog with `flags`: its frames."""
    cli(
        "transfer",
        "--source-ref", d / "cat-reference.obj",
        "--source", d / "cat-run",
        "--target", d / "dog-reference.obj",
        "--markers", d / "markers-cat-dog.json",
        *flags,
        "--out", out,
    )
    return morphkit.read_animation(out)[0]


def test_keyword_defaults_are_the_library_defaults():
    """Every keyword left out is the library's default (issue 55), which the CLI uses too."""
    d = morphkit.transfer_defaults()
    assert set(d) == {"refine", "combine", "translation", "local_stretch", "area_weighted", "fold_guard"}
    # The defaults of issue 40 (docs/choices.md, "Transfer defaults").
    assert d["refine"] and d["local_stretch"] and d["area_weighted"] and d["fold_guard"]
    assert (d["combine"], d["translation"]) == ("inverse-distance", "follow")
    V, F = tube(8, 8)
    c = morphkit.Correspondence.identity(V, F)
    t = morphkit.Transfer(V, F, V, F, c)
    assert t.options == {k: v for k, v in d.items() if k != "refine"}
    old = morphkit.Transfer(V, F, V, F, c, local_stretch=False, area_weighted=False, combine="mean",
                            translation="fixed")
    assert old.options == dict(t.options, local_stretch=False, area_weighted=False, combine="mean",
                               translation="fixed")
    markers = [[k, k] for k in range(0, len(V), 7)]
    assert morphkit.Correspondence.from_markers(V, F, V, F, markers).refined == d["refine"]
    assert not morphkit.Correspondence.from_markers(V, F, V, F, markers, refine=False).refined
    # A rig's defaults are `morphkit rig`'s: an unrefined correspondence, the world frame.
    r = morphkit.rig_defaults()
    assert set(r) == {"refine", "combine", "local_stretch", "area_weighted", "fold_guard"}
    assert not r["refine"] and not r["local_stretch"] and not r["area_weighted"]


def test_cat_dog_equals_the_cli(tmp_path, cli, cat_dog):
    """The module's keyword defaults are the CLI's defaults (issue 55: one answer per entry
    point), and the old configuration is the CLI's with its opt-out flags."""
    VS, FS, VT, FT, frames = cat_dog_inputs(cat_dog)
    markers = cat_dog / "markers-cat-dog.json"
    c = morphkit.Correspondence.from_markers(VS, FS, VT, FT, markers)
    assert len(c.marker_residuals) == 41 and c.refined
    ours = morphkit.Transfer(VS, FS, VT, FT, c).transfer_many(frames[:4])
    theirs = cli_transfer(cli, cat_dog, tmp_path / "dog")
    assert np.abs(ours - theirs[:4]).max() <= 1e-9 * diag(VT)
    plain_c = morphkit.Correspondence.from_markers(VS, FS, VT, FT, markers, refine=False)
    plain = morphkit.Transfer(
        VS, FS, VT, FT, plain_c, local_stretch=False, area_weighted=False
    ).transfer_many(frames[:4])
    theirs = cli_transfer(
        cli, cat_dog, tmp_path / "dog-plain", "--no-refine", "--world-frame", "--uniform-weights"
    )
    assert np.abs(plain - theirs[:4]).max() <= 1e-9 * diag(VT)
    assert np.abs(plain - ours).max() > 1e-4 * diag(VT)


def test_local_stretch_self_transfer_is_exact_and_the_guard_needs_it():
    V, F = tube()
    c = morphkit.Correspondence.identity(V, F)
    frames = np.stack([bend(V, a) for a in (0.4, 1.1)])
    for guard in (True, False):
        t = morphkit.Transfer(
            V, F, V, F, c, translation="fixed", local_stretch=True, area_weighted=True, fold_guard=guard
        )
        assert np.abs(t.transfer_many(frames) - frames).max() < 1e-8 * diag(V)
    with pytest.raises(morphkit.TransferError, match="fold_guard"):
        morphkit.Transfer(V, F, V, F, c, local_stretch=False, fold_guard=False)


def test_cat_dog_best_configuration_equals_the_cli(tmp_path, cli, cat_dog):
    """refine, local_stretch and area_weighted reach the library as the CLI's flags do."""
    VS, FS, VT, FT, frames = cat_dog_inputs(cat_dog)
    markers = cat_dog / "markers-cat-dog.json"
    plain_c = morphkit.Correspondence.from_markers(VS, FS, VT, FT, markers, refine=False)
    c = morphkit.Correspondence.from_markers(VS, FS, VT, FT, markers, refine=True)
    assert c.matches != plain_c.matches
    t = morphkit.Transfer(VS, FS, VT, FT, c, local_stretch=True, area_weighted=True)
    ours = t.transfer_many(frames[:3])
    plain = morphkit.Transfer(
        VS, FS, VT, FT, plain_c, local_stretch=False, area_weighted=False
    ).transfer_many(frames[:3])
    assert np.abs(ours - plain).max() > 1e-4 * diag(VT)
    flags = ("--refine", "--local-stretch", "--area-weighted")
    theirs = cli_transfer(cli, cat_dog, tmp_path / "dog", *flags)
    assert np.abs(ours - theirs[:3]).max() <= 1e-9 * diag(VT)


def test_rig_onto_a_rotated_scaled_copy_and_equal_to_the_cli(tmp_path, cli):
    V, F = tube()
    shapes = np.stack([bend(V, 0.6), bend(V, 1.2)])
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    scale, shift = 1.7, np.array([3.0, -1.0, 0.5])
    VT = scale * V @ R.T + shift
    corr = morphkit.Correspondence.identity(V, F)
    rig = morphkit.RigTransfer(V, F, VT, F, corr)
    out = rig.transfer_many(shapes)
    expected = scale * shapes @ R.T + shift  # the neutral stays: vertex 0 is fixed by the bend
    assert np.abs(out - expected).max() < 1e-8 * diag(VT)
    np.testing.assert_array_equal(rig.transfer(shapes[1]), out[1])
    with pytest.raises(morphkit.TransferError, match="vertices"):
        rig.transfer(V[:-1])
    # The CLI writes the same shapes as named morph targets.
    morphkit.write(tmp_path / "neutral.obj", V, F)
    morphkit.write(tmp_path / "head.obj", VT, F)
    for name, X in zip(("smile", "frown"), shapes):
        morphkit.write(tmp_path / f"{name}.obj", X, F)
    corr.save(tmp_path / "c.json")
    cli("rig", "--source-neutral", tmp_path / "neutral.obj",
        "--source-shapes", tmp_path / "smile.obj", tmp_path / "frown.obj",
        "--target", tmp_path / "head.obj", "--correspondence", tmp_path / "c.json",
        "--out", tmp_path / "rig.glb")
    _, _, T, names = morphkit.read_morphs(tmp_path / "rig.glb")
    assert names == ["smile", "frown"]
    assert np.abs(T - out).max() < 1e-6 * diag(VT)  # glTF stores float32
