"""A user's glTF rig through Python: read_rig, write_rig and write_animation(template=...)
keep the asset (materials, other nodes, transforms, extras, animations) and edit only the
morph targets and weights animations of its mesh."""

import base64
import json
import os
import subprocess

import numpy as np
import pytest

import morphkit


def _asset(path):
    """A hand-made .gltf: a tetrahedron with one morph target ('up'), a named material, a node
    scaled by 100, a second node without a mesh, scene extras and a weights animation 'talk'."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.uint16)
    D = np.zeros_like(V)
    D[3] = [0, 0, 0.5]
    times = np.array([0.0, 0.5, 1.0], dtype=np.float32)
    weights = np.array([0.0, 1.0, 0.25], dtype=np.float32)
    chunks = [V.tobytes(), D.tobytes(), F.tobytes(), times.tobytes(), weights.tobytes()]
    offsets = np.cumsum([0] + [len(c) for c in chunks])
    data = b"".join(chunks)
    views = [
        {"buffer": 0, "byteOffset": int(offsets[i]), "byteLength": len(chunks[i])} for i in range(5)
    ]
    doc = {
        "asset": {"version": "2.0", "generator": "hand"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1], "extras": {"studio": "test"}}],
        "nodes": [
            {"name": "head", "mesh": 0, "scale": [100, 100, 100]},
            {"name": "lamp", "translation": [1, 2, 3]},
        ],
        "meshes": [
            {
                "name": "face",
                "primitives": [
                    {"attributes": {"POSITION": 0}, "indices": 2, "material": 0, "targets": [{"POSITION": 1}]}
                ],
                "weights": [0.0],
                "extras": {"targetNames": ["up"]},
            }
        ],
        "materials": [{"name": "skin", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.5, 0.4, 1]}}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0.5]},
            {"bufferView": 2, "componentType": 5123, "count": 12, "type": "SCALAR"},
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0], "max": [1]},
            {"bufferView": 4, "componentType": 5126, "count": 3, "type": "SCALAR"},
        ],
        "bufferViews": views,
        "buffers": [
            {"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}
        ],
        "animations": [
            {
                "name": "talk",
                "samplers": [{"input": 3, "output": 4, "interpolation": "LINEAR"}],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            }
        ],
    }
    path.write_text(json.dumps(doc))
    return V.astype(np.float64), D.astype(np.float64)


def _valid(path):
    """The Khronos validator finds no error (when CI gives it: MORPHKIT_GLTF_VALIDATOR)."""
    validator = os.environ.get("MORPHKIT_GLTF_VALIDATOR")
    if not validator:
        return
    out = subprocess.run(["node", validator, str(path)], capture_output=True, text=True)
    assert out.returncode == 0 and ": 0 errors" in out.stdout + out.stderr, out.stdout + out.stderr


def _kept(a, b):
    """The parts of the document an edit of the mesh's targets must not change."""
    for key in ("materials",):
        assert a[key] == b[key], key
    assert [n.get("name") for n in a["nodes"]] == [n.get("name") for n in b["nodes"]]
    assert a["nodes"][0]["scale"] == b["nodes"][0]["scale"] == [100, 100, 100]
    assert a["nodes"][1]["translation"] == b["nodes"][1]["translation"]
    assert a["scenes"][0]["extras"] == b["scenes"][0]["extras"]
    assert a["meshes"][0]["name"] == b["meshes"][0]["name"]
    assert a["meshes"][0]["primitives"][0]["material"] == 0


def test_read_rig_gives_base_targets_names_and_the_animation(tmp_path):
    V, D = _asset(tmp_path / "rig.gltf")
    _valid(tmp_path / "rig.gltf")
    rig = morphkit.read_rig(tmp_path / "rig.gltf")
    np.testing.assert_array_equal(rig["base"], V)
    assert rig["faces"].shape == (4, 3)
    assert rig["names"] == ["up"]
    np.testing.assert_array_equal(rig["targets"][0], V + D)
    np.testing.assert_array_equal(rig["times"], [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(rig["weights"], [[0.0], [1.0], [0.25]])
    assert rig["animation"] == "talk" and rig["animations"] == ["talk"]
    with pytest.raises(morphkit.FileError, match="no animation named 'walk'"):
        morphkit.read_rig(tmp_path / "rig.gltf", animation="walk")


def test_write_rig_adds_targets_to_the_users_asset(tmp_path):
    V, D = _asset(tmp_path / "rig.gltf")
    smile = V + [[0.1, 0, 0]] * 4
    morphkit.write_rig(tmp_path / "out.gltf", tmp_path / "rig.gltf", smile[None], ["smile"])
    a = json.loads((tmp_path / "rig.gltf").read_text())
    b = json.loads((tmp_path / "out.gltf").read_text())
    _kept(a, b)
    _valid(tmp_path / "out.gltf")
    rig = morphkit.read_rig(tmp_path / "out.gltf")
    assert rig["names"] == ["up", "smile"]
    assert np.abs(rig["targets"][1] - smile).max() < 1e-6
    np.testing.assert_array_equal(rig["targets"][0], V + D)
    # The existing animation gets weight 0 for the new target.
    np.testing.assert_array_equal(rig["weights"], [[0.0, 0.0], [1.0, 0.0], [0.25, 0.0]])
    # A name the mesh has replaces that target; the template itself is never written.
    morphkit.write_rig(tmp_path / "out2.gltf", tmp_path / "rig.gltf", smile[None], ["up"])
    rig = morphkit.read_rig(tmp_path / "out2.gltf")
    assert rig["names"] == ["up"] and np.abs(rig["targets"][0] - smile).max() < 1e-6
    assert json.loads((tmp_path / "rig.gltf").read_text()) == a
    with pytest.raises(morphkit.MeshError, match="2 names for 1 targets"):
        morphkit.write_rig(tmp_path / "x.gltf", tmp_path / "rig.gltf", smile[None], ["a", "b"])
    assert not (tmp_path / "x.gltf").exists()


def test_write_animation_into_a_template_adds_a_clip(tmp_path):
    V, D = _asset(tmp_path / "rig.gltf")
    rig = morphkit.read_rig(tmp_path / "rig.gltf")
    frames = np.stack([V + w[0] * D * 1.5 for w in rig["weights"]])
    morphkit.write_animation(
        tmp_path / "phys.glb", frames, template=tmp_path / "rig.gltf", clip="talk-physical", times=rig["times"]
    )
    _valid(tmp_path / "phys.glb")
    out = morphkit.read_rig(tmp_path / "phys.glb", animation="talk-physical")
    assert out["animations"] == ["talk", "talk-physical"]
    assert out["names"][0] == "up" and len(out["names"]) == 4
    np.testing.assert_array_equal(out["times"], [0.0, 0.5, 1.0])
    # Key k shows frame k alone.
    np.testing.assert_array_equal(out["weights"][:, 1:], np.eye(3))
    assert np.abs(out["targets"][1:] - frames).max() < 1e-6
    V2, F2 = morphkit.read(tmp_path / "phys.glb")
    np.testing.assert_array_equal(V2, V)
    with pytest.raises(morphkit.MeshError, match="faces are needed"):
        morphkit.write_animation(tmp_path / "y.glb", frames)


def test_read_rig_reads_a_split_frame_sequence_as_what_it_is(tmp_path):
    """450 frames written to a .glb with one target per frame are split into meshes of at most
    200 targets (what WebGL2 viewers play; by default such a sequence is a compact clip,
    test_io.py); read_rig gives all 449 targets, one weight per target and one key and one
    time per frame, so the README's recipe gets consistent arrays (issue 55)."""
    from conftest import bend, tube

    V, F = tube(rings=4, around=6)
    frames = np.stack([bend(V, 1e-3 + 2.0 * k / 449) for k in range(450)])
    morphkit.write_animation(tmp_path / "long.glb", frames, F, fps=24.0, per_frame_targets=True)
    rig = morphkit.read_rig(tmp_path / "long.glb")
    assert rig["targets"].shape == (449, len(V), 3)
    assert rig["weights"].shape == (450, 449)
    assert rig["times"].shape == (450,)
    np.testing.assert_allclose(rig["times"], np.arange(450) / 24.0, atol=1e-5)
    # Key k shows frame k: the weights blend the targets back into the frames.
    linear = rig["base"] + np.einsum("kt,tvi->kvi", rig["weights"], rig["targets"] - rig["base"])
    assert np.abs(linear - frames).max() < 1e-5
    # Adding a clip to the split sequence is refused, naming the file and what it is.
    with pytest.raises(morphkit.FileError, match=r"long\.glb.*frame sequence morphkit split into 3 meshes"):
        morphkit.write_animation(tmp_path / "x.glb", frames[:2], template=tmp_path / "long.glb")
    assert not (tmp_path / "x.glb").exists()
