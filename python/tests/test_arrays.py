"""Bad arrays give MeshError (a ValueError) naming the argument and the row; views work."""

import numpy as np
import pytest

import morphkit
from conftest import bend, tube


def blend_of(V, F):
    return morphkit.PhysicalBlend(V, [bend(V, 1.0)], F)


def test_wrong_shape():
    V, F = tube(6, 6)
    with pytest.raises(morphkit.MeshError, match=r"base V: expected shape \(n, 3\)"):
        blend_of(V[:, :2], F)
    with pytest.raises(morphkit.MeshError, match="triangles"):
        morphkit.PhysicalBlend(V, [V], F[:, :2])


def test_wrong_dtype():
    V, F = tube(6, 6)
    with pytest.raises(morphkit.MeshError, match="float64"):
        morphkit.PhysicalBlend(V.astype(np.complex128), [V], F)
    with pytest.raises(morphkit.MeshError, match="integer"):
        morphkit.PhysicalBlend(V, [V], F.astype(float))
    with pytest.raises(ValueError):
        morphkit.PhysicalBlend("not an array", [V], F)


def test_nan_and_out_of_range():
    V, F = tube(6, 6)
    bad = V.copy()
    bad[5, 2] = np.nan
    with pytest.raises(morphkit.MeshError, match="row 5"):
        morphkit.PhysicalBlend(bad, [V], F)
    with pytest.raises(morphkit.MeshError, match="targets\\[0\\]: row 5"):
        morphkit.PhysicalBlend(V, [bad], F)
    F2 = F.copy()
    F2[3, 1] = len(V)
    with pytest.raises(morphkit.MeshError, match="face 3"):
        morphkit.PhysicalBlend(V, [V], F2)
    F2[3, 1] = -1
    with pytest.raises(morphkit.MeshError, match="face 3"):
        morphkit.PhysicalBlend(V, [V], F2)


@pytest.mark.parametrize(
    "dtype", [np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64]
)
def test_every_integer_dtype_of_faces(dtype):
    V, F = tube(6, 6)  # 42 vertices: every index fits int8
    ref = blend_of(V, F).solve(0.5)
    got = blend_of(V, F.astype(dtype)).solve(0.5)
    np.testing.assert_array_equal(got, ref)
    assert morphkit.metrics(V, V, F.astype(dtype))["edge_length_rms"] == 0.0


def test_negative_and_large_indices_of_small_dtypes():
    V, F = tube(6, 6)
    for dtype in (np.int8, np.int16):
        F2 = F.astype(dtype)
        F2[3, 1] = -1
        with pytest.raises(morphkit.MeshError, match="base F: face 3 has a negative vertex index -1"):
            blend_of(V, F2)
    F2 = F.astype(np.uint8)
    F2[4, 2] = 200
    with pytest.raises(morphkit.MeshError, match=r"base F: face 4 has vertex index 200 out of range \(0..42\)"):
        blend_of(V, F2)
    with pytest.raises(morphkit.MeshError, match="integer"):
        blend_of(V, F.astype(bool))


def test_target_vertex_count():
    V, F = tube(6, 6)
    with pytest.raises(morphkit.MeshError, match="expected"):
        morphkit.PhysicalBlend(V, [V[:-1]], F)


def test_strided_and_converted_inputs_equal_contiguous():
    V, F = tube(8, 8)
    B = bend(V, 1.2)
    ref = morphkit.PhysicalBlend(V, [B], F).solve(0.5)
    # Fortran order, a strided view into a wider array, float32 and int32 inputs.
    wide = np.zeros((len(V), 6))
    wide[:, ::2] = V
    Vs = wide[:, ::2]
    assert not Vs.flags.c_contiguous
    got = morphkit.PhysicalBlend(np.asfortranarray(Vs), [B], F.astype(np.int32)).solve(0.5)
    np.testing.assert_array_equal(got, ref)
    got32 = morphkit.PhysicalBlend(V.astype(np.float32), [B.astype(np.float32)], F).solve(0.5)
    assert np.abs(got32 - ref).max() < 1e-5


def test_returned_arrays_are_new():
    V, F = tube(6, 6)
    b = blend_of(V, F)
    x = b.solve(0.0)
    x[:] = 0.0
    assert np.abs(b.solve(0.0) - V).max() < 1e-6
