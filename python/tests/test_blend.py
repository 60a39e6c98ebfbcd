"""PhysicalBlend: endpoints, order independence, threads, pulls, and equality with the CLI."""

import threading

import numpy as np
import pytest

import morphkit
from conftest import bend, diag, grid, tube


@pytest.fixture(scope="module")
def rig():
    V, F = tube()
    return V, bend(V, 2.0), F


def test_endpoints_are_the_shapes(rig):
    V, B, F = rig
    b = morphkit.PhysicalBlend(V, [B], F)
    d = diag(V)
    assert np.abs(b.solve(0.0) - V).max() <= 1e-6 * d
    assert np.abs(b.solve(1.0) - B).max() <= 1e-6 * d
    assert np.abs(b.solve([0.0, 1.0], convex=True) - B).max() <= 1e-6 * d
    assert b.last_stats["converged"] is True


def test_physical_beats_linear(rig):
    V, B, F = rig
    x = morphkit.PhysicalBlend(V, [B], F).solve(0.5)
    rest = bend(V, 1.0)  # the same tube bent halfway: lengths of the rest shape
    phys = morphkit.metrics(rest, x, F)["edge_length_rms"]
    lin = morphkit.metrics(rest, 0.5 * (V + B), F)["edge_length_rms"]
    assert phys < 0.2 * lin, (phys, lin)


def test_function_of_the_weights_alone(rig):
    V, B, F = rig
    b = morphkit.PhysicalBlend(V, [B], F)
    forward = [b.solve(a) for a in (0.25, 0.5, 0.75)]
    backward = [b.solve(a) for a in (0.75, 0.5, 0.25)][::-1]
    for x, y in zip(forward, backward):
        assert np.abs(x - y).max() <= 1e-12 * diag(V)
    many = b.solve_many([[0.25], [0.5], [0.75]], threads=2)
    for x, y in zip(forward, many):
        assert np.abs(x - y).max() <= 1e-12 * diag(V)


def test_continuation_along_the_ray(rig):
    # continuation_steps: each frame solved along its ray in K steps; on this tube (one
    # equilibrium) the same frames as the canonical start to the tolerance, a function of the
    # weights alone, the shape itself at weight 1, and more Newton work per frame.
    V, B, F = rig
    plain = morphkit.PhysicalBlend(V, [B], F)
    along = morphkit.PhysicalBlend(V, [B], F, continuation_steps=4)
    d = diag(V)
    x = along.solve(0.6)
    work = along.last_stats["newton_iterations"]
    assert np.abs(x - plain.solve(0.6)).max() <= 1e-4 * d
    assert work > plain.last_stats["newton_iterations"]
    along.solve(0.3)
    assert np.array_equal(along.solve(0.6), x)
    assert np.array_equal(along.solve(1.0), B)
    for bad in (65, -1):
        with pytest.raises(ValueError):
            morphkit.PhysicalBlend(V, [B], F, continuation_steps=bad)
    with pytest.raises(TypeError):
        morphkit.PhysicalBlend(V, [B], F, continuation_steps=2.5)


def test_stats_and_summary(rig):
    V, B, F = rig
    b = morphkit.PhysicalBlend(V, [B], F)
    assert b.last_stats is None
    b.solve(0.4)  # not a sample weight of the sampled start (there it starts converged)
    s = b.last_stats
    assert s["converged"] and s["gradient_norm"] <= s["gradient_tolerance"]
    assert s["newton_iterations"] >= 1
    assert b.summary["vertices"] == len(V) and b.summary["springs"] > len(F)
    assert b.num_targets == 1


def test_bad_weights(rig):
    V, B, F = rig
    b = morphkit.PhysicalBlend(V, [B], F)
    with pytest.raises(morphkit.BlendError):
        b.solve([0.5, 0.5])
    with pytest.raises(morphkit.BlendError):
        b.solve(float("nan"))
    with pytest.raises(morphkit.BlendError):
        b.solve(1e6)
    with pytest.raises(morphkit.BlendError, match="fixed"):
        morphkit.PhysicalBlend(V, [B], F, fixed="sometimes")


def test_pull_holds_the_vertex_and_decays():
    V, F = grid(10)
    boundary = [i for i in range(len(V)) if V[i, 0] <= 1.0]  # two columns: no hinge axis
    b = morphkit.PhysicalBlend(V, [V.copy()], F, fixed=boundary)
    tip = int(np.argmax(V[:, 0] + 1e-3 * V[:, 1]))  # a far corner
    goal = V[tip] + [0.0, 0.0, 2.0]
    x = b.solve(0.0, pulls={tip: tuple(goal)})
    assert np.linalg.norm(x[tip] - goal) < 1e-3
    assert np.abs(x[boundary] - V[boundary]).max() < 1e-9
    dz = x[:, 2]
    near = np.argsort(np.linalg.norm(V - V[tip], axis=1))
    assert dz[near[1]] > dz[near[-1]]
    with pytest.raises(morphkit.BlendError, match=r"pulls vertex = 121 is not a vertex index"):
        b.solve(0.0, pulls={len(V): (0, 0, 0)})


def test_threads_run_in_parallel_without_interference(rig):
    V, B, F = rig
    blends = [morphkit.PhysicalBlend(V, [B], F) for _ in range(2)]
    out = [None, None]

    def work(i):
        out[i] = blends[i].solve(0.3 + 0.4 * i)

    ts = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    ref = morphkit.PhysicalBlend(V, [B], F)
    assert np.abs(out[0] - ref.solve(0.3)).max() <= 1e-12 * diag(V)
    assert np.abs(out[1] - ref.solve(0.7)).max() <= 1e-12 * diag(V)


def test_equals_the_cli(tmp_path, cli, data):
    rest = data("cragl-bending-cylinder/cylinder-rest.obj")
    bent = data("cragl-bending-cylinder/cylinder-bend-4.obj")
    out = tmp_path / "half.obj"
    cli("blend", "--base", rest, "--target", bent, "--alpha", "0.5", "--out", out)
    V0, F = morphkit.read(rest)
    V1, _ = morphkit.read(bent)
    x = morphkit.PhysicalBlend(V0, [V1], F).solve(0.5)
    y, _ = morphkit.read(out)
    # OBJ stores the CLI's result with round-trip precision; frames agree to round-off.
    assert np.abs(x - y).max() <= 1e-12 * diag(V0)


def test_real_horse_endpoint(data):
    V0, F = morphkit.read(data("sumner-horse-camel/horse-reference.obj.gz"))
    V1, _ = morphkit.read(data("sumner-horse-camel/horse-05.obj.gz"))
    b = morphkit.PhysicalBlend(V0, [V1], F)
    assert np.abs(b.solve(1.0) - V1).max() <= 1e-6 * diag(V0)


def test_interior_and_anchor():
    from conftest import capped_tube

    V, F = capped_tube()
    assert morphkit.metrics(V, V, F)["volume"] > 0  # closed and outward
    B = bend(V, 1.5)
    b = morphkit.PhysicalBlend(V, [B], F, interior="lattice", anchor="auto")
    info = b.summary["interior"]
    assert info["interior_vertices"] > 0 and info["anchor_vertices"] == 8
    d = diag(V)
    assert np.abs(b.solve(0.0) - V).max() <= 1e-6 * d
    assert np.abs(b.solve(1.0) - B).max() <= 1e-6 * d
    half = b.solve(0.5)
    assert b.last_stats["converged"]
    vol = morphkit.metrics(V, half, F)["volume_ratio"]
    assert 0.9 < vol < 1.1
    with pytest.raises(morphkit.BlendError, match="interior"):
        morphkit.PhysicalBlend(V, [B], F, interior="voxels")


def test_pulls_with_an_interior_and_an_anchor():
    from conftest import capped_tube

    V, F = capped_tube()
    B = bend(V, 1.5)
    tip = int(np.argmax(V[:, 0]))
    for anchor in (None, "auto"):
        b = morphkit.PhysicalBlend(V, [B], F, interior="lattice,2", anchor=anchor)
        free = b.solve(0.5)
        goal = free[tip] + np.array([0.0, 0.2, 0.0])
        x = b.solve(0.5, pulls={tip: tuple(goal)})
        assert b.last_stats["converged"]
        # A hard pull is met exactly, in world coordinates also when the solve runs in the
        # anchor's frame.
        assert np.abs(x[tip] - goal).max() <= 1e-9 * diag(V), anchor
        assert np.abs(x - free).max() > 0.1


def test_predictor_previews_while_the_blend_solves(rig):
    V, B, F = rig
    b = morphkit.PhysicalBlend(V, [B], F)
    d = diag(V)
    preview = b.predictor()
    assert isinstance(preview, morphkit.Predictor)
    assert np.abs(preview.predict(0.0) - V).max() <= 1e-12 * d
    assert np.abs(b.predict([0.0, 1.0], convex=True) - B).max() <= 1e-12 * d
    solved = {}
    t = threading.Thread(target=lambda: solved.setdefault("x", b.solve(0.4)))
    t.start()
    previews = [preview.predict(a) for a in (0.1, 0.3, 0.4)]  # while the solve runs
    t.join()
    x = solved["x"]
    assert b.last_stats["newton_iterations"] > 0
    lin = 0.6 * V + 0.4 * B
    assert np.abs(previews[2] - x).max() < 0.5 * np.abs(lin - x).max()
    assert np.array_equal(previews[2], preview.predict(0.4))
    with pytest.raises(morphkit.BlendError, match="weight"):
        preview.predict([0.5, 0.5])


def test_predictor_with_an_interior_previews_the_volumetric_start():
    from conftest import capped_tube

    V, F = capped_tube()
    B = bend(V, 1.5)
    for anchor in (None, "auto"):
        b = morphkit.PhysicalBlend(V, [B], F, interior="lattice", anchor=anchor)
        preview = b.predictor()
        assert np.abs(preview.predict(0.0) - V).max() < 1e-9
        assert np.abs(preview.predict(1.0) - B).max() < 1e-9
        p = b.predict(0.5)
        assert p.shape == V.shape
        assert np.array_equal(p, preview.predict(0.5))
        x = b.solve(0.5)
        lin = 0.5 * (V + B)
        assert np.abs(p - x).max() < 0.5 * np.abs(lin - x).max()


def test_tetgen_interior():
    import os
    import shutil

    if shutil.which("tetgen") is None:
        if os.environ.get("MORPHKIT_REQUIRE_TETGEN"):
            pytest.fail("MORPHKIT_REQUIRE_TETGEN is set but no tetgen is on the PATH")
        pytest.skip("no tetgen on the PATH")
    from conftest import capped_tube

    V, F = capped_tube()
    B = bend(V, 1.5)
    b = morphkit.PhysicalBlend(V, [B], F, interior="tetgen")
    assert b.summary["interior"]["interior_vertices"] > 0
    d = diag(V)
    assert np.abs(b.solve(1.0) - B).max() <= 1e-6 * d
    half = b.solve(0.5)
    assert b.last_stats["converged"]
    assert 0.9 < morphkit.metrics(V, half, F)["volume_ratio"] < 1.1


def test_sampled_start_agrees_with_the_plain_start(rig):
    V, B, F = rig
    d = diag(V)
    sampled = morphkit.PhysicalBlend(V, [B], F)
    plain = morphkit.PhysicalBlend(V, [B], F, sampled_start=False)
    for a in (0.3, 0.5, 0.8):
        x, y = sampled.solve(a), plain.solve(a)
        assert sampled.last_stats["converged"] and plain.last_stats["converged"]
        assert np.abs(x - y).max() <= 1e-5 * d, a
        if a == 0.5:
            # At a sample weight the sampled start is that sample's equilibrium.
            assert sampled.last_stats["newton_iterations"] == 0
            assert plain.last_stats["newton_iterations"] >= 1


def test_thin_bands_follow_the_predictor():
    # A ring 3 vertices wide and 40 around (an eye strip), squashed by its target: a thin band.
    V, F = tube(rings=2, around=40, length=0.2, radius=1.0)
    B = V * [1.0, 0.2, 1.0]
    moving = int((np.abs(B - V).max(axis=1) > 1e-9).sum())  # the rest is fixed (auto)
    b = morphkit.PhysicalBlend(V, [B], F)
    assert b.summary["band_vertices"] == moving
    assert np.array_equal(b.solve(0.4), b.predict(0.4))
    springs = morphkit.PhysicalBlend(V, [B], F, thin_band_rings=0)
    assert springs.summary["band_vertices"] == 0
    assert springs.solve(0.4).shape == V.shape


def test_tether_is_weak_pulls_towards_the_predictor_and_is_checked(rig):
    V, B, F = rig
    d = diag(V)
    frames = {t: morphkit.PhysicalBlend(V, [B], F, tether=t).solve(0.4) for t in (0.0, 1e-5, 1.0)}
    p = morphkit.PhysicalBlend(V, [B], F).predict(0.4)
    far = {t: np.linalg.norm(x - p, axis=1).max() for t, x in frames.items()}
    # The default is weak (it moves the frame by a small part of the diagonal, and less than
    # the equilibrium's distance from the predictor); a stiff tether pulls towards the predictor.
    moved = np.abs(frames[1e-5] - frames[0.0]).max()
    assert moved <= 1e-3 * d and moved <= 0.1 * far[0.0], (moved, far)
    assert far[1.0] < 0.5 * far[1e-5] and far[0.0] > 1e-4 * d, far
    with pytest.raises(morphkit.BlendError, match="tether"):
        morphkit.PhysicalBlend(V, [B], F, tether=-1.0)
