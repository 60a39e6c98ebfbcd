"""Reading and writing through the library's readers and writers."""

import numpy as np
import pytest

import morphkit
from conftest import diag, grid, tube


@pytest.mark.parametrize("ext", ["obj", "obj.gz", "ply", "off", "glb", "gltf"])
def test_mesh_round_trip(tmp_path, ext):
    V, F = tube()
    path = tmp_path / f"tube.{ext}"
    morphkit.write(path, V, F)
    V2, F2 = morphkit.read(path)
    assert V2.shape == V.shape and V2.dtype == np.float64
    assert F2.dtype == np.int64
    np.testing.assert_array_equal(F2, F)
    tol = 1e-6 * diag(V) if ext in ("glb", "gltf") else 1e-12 * diag(V)  # glTF stores float32
    assert np.abs(V2 - V).max() <= tol


def test_morphs_round_trip(tmp_path):
    V, F = grid(4)
    T = np.stack([V + [0, 0, 1.0], V * 2.0])
    morphkit.write_morphs(tmp_path / "m.glb", V, F, T, names=["up", "big"])
    V2, F2, T2, names = morphkit.read_morphs(tmp_path / "m.glb")
    assert names == ["up", "big"]
    assert T2.shape == (2, len(V), 3)
    assert np.abs(T2 - T).max() < 1e-5
    np.testing.assert_array_equal(F2, F)


@pytest.mark.parametrize("out", ["frames", "anim.glb", "anim.pc2"])
def test_animation_round_trip(tmp_path, out):
    V, F = tube(8, 6)
    frames = np.stack([V + [0.1 * k, 0, 0] for k in range(5)])
    path = tmp_path / out
    morphkit.write_animation(path, frames, F, fps=30)
    ref = None
    if out.endswith(".pc2"):
        ref = tmp_path / "ref.obj"
        morphkit.write(ref, V, F)
    back, F2, names = morphkit.read_animation(path, reference=ref)
    assert back.shape == frames.shape
    assert np.abs(back - frames).max() < 1e-5 * diag(V)
    assert len(names) == 5
    np.testing.assert_array_equal(F2, F)


def test_a_long_animation_is_a_compact_clip(tmp_path):
    # More frames than max_targets: a few morph targets at per-frame weights, every frame within
    # the tolerance as read back; per_frame_targets keeps one target per frame.
    V, F = tube(8, 6)
    t = np.linspace(0.0, 1.0, 40)[:, None, None]
    frames = V[None] + np.sin(np.pi * 2 * t) * [0.3, 0, 0] + np.sin(np.pi * 3 * t) ** 2 * V * [0, 0.2, 0]
    compact, exact = tmp_path / "compact.glb", tmp_path / "exact.glb"
    morphkit.write_animation(compact, frames, F, max_targets=10)
    morphkit.write_animation(exact, frames, F, max_targets=10, per_frame_targets=True)
    _, _, targets, _ = morphkit.read_morphs(compact)
    assert 2 <= len(targets) <= 10
    assert len(morphkit.read_morphs(exact)[2]) == 39
    for path, tol in ((compact, 1e-3), (exact, 1e-6)):
        back, _, _ = morphkit.read_animation(path)
        assert np.abs(back - frames).max() <= tol * diag(V)
    assert compact.stat().st_size * 3 < exact.stat().st_size
    with pytest.raises(ValueError, match="finite positive"):
        morphkit.write_animation(tmp_path / "x.glb", frames, F, clip_tolerance=0.0)
    with pytest.raises(ValueError, match="not both"):
        morphkit.write_animation(tmp_path / "x.glb", frames, F, clip_tolerance=1e-3, per_frame_targets=True)
    assert not (tmp_path / "x.glb").exists()


def test_quantize_and_meshopt_make_smaller_files_that_read_back(tmp_path):
    V, F = tube(16, 12)
    t = np.linspace(0.0, 1.0, 12)[:, None, None]
    frames = V[None] + np.sin(np.pi * t) * V * [0.2, 0, 0.1]
    paths = {}
    for q in (False, True):
        for m in (False, True):
            paths[q, m] = tmp_path / f"a-{int(q)}{int(m)}.glb"
            morphkit.write_animation(paths[q, m], frames, F, quantize=q, meshopt=m)
    for q in (False, True):
        plain, _, _ = morphkit.read_animation(paths[q, False])
        packed, _, _ = morphkit.read_animation(paths[q, True])
        np.testing.assert_array_equal(plain, packed)  # meshopt is lossless
        assert np.abs(packed - frames).max() <= (1e-4 if q else 1e-6) * diag(V)
        assert b"EXT_meshopt_compression" in paths[q, True].read_bytes()[:4096]
    assert paths[True, True].stat().st_size < paths[True, False].stat().st_size * 3 // 4
    assert paths[True, False].stat().st_size < paths[False, False].stat().st_size
    with pytest.raises(ValueError, match="keeps its own encoding"):
        morphkit.write_animation(tmp_path / "x.glb", frames, template=paths[False, False], meshopt=True)
    assert not (tmp_path / "x.glb").exists()


def test_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(morphkit.FileError) as e:
        morphkit.read(tmp_path / "nope.obj")
    assert isinstance(e.value, OSError) and isinstance(e.value, ValueError)
    assert "nope.obj" in str(e.value)


def test_parse_error_names_the_line(tmp_path):
    p = tmp_path / "bad.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    with pytest.raises(morphkit.FileError) as e:
        morphkit.read(p)
    assert "bad.obj" in str(e.value)


def test_unknown_extension_is_refused(tmp_path):
    V, F = grid(2)
    with pytest.raises(morphkit.FileError):
        morphkit.write(tmp_path / "x.xyz", V, F)
    assert not (tmp_path / "x.xyz").exists()


def test_real_horse_reads(data):
    V, F = morphkit.read(data("sumner-horse-camel/horse-reference.obj.gz"))
    assert V.shape == (8431, 3) and F.shape == (16843, 3)
