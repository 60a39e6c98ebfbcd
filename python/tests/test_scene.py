"""SceneBlend: obstacles (Ma et al. Fig. 2 analogue) and keyed pulls, with bad input refused."""

import numpy as np
import pytest

import morphkit
from conftest import data_file, diag, grid, tube


@pytest.fixture(scope="module")
def cylinder():
    d = data_file("cragl-bending-cylinder")
    V0, F = morphkit.read(d / "cylinder-rest.obj")
    V1, _ = morphkit.read(d / "cylinder-bend-4.obj")
    return V0, V1, F


def test_bar_in_the_path_is_not_penetrated(cylinder):
    V0, V1, F = cylinder
    bar = morphkit.Obstacle.cylinder(0.2, 2.0, name="bar", keys=[(0, (1.35, 0.0, 0.95))])
    scene = morphkit.SceneBlend(V0, [V1], F, obstacles=[bar])
    free = morphkit.PhysicalBlend(V0, [V1], F)
    d = diag(V0)
    touched = 0
    for a in (0.0, 0.5, 1.0):
        x = scene.solve(a)
        s = scene.last_stats
        assert s["collision"]["resolved"] and s["collision"]["max_penetration"] <= 1e-4 * d
        # Inside test of the bar (axis along y through (1.35, ·, 0.95)): nothing deeper.
        r = np.hypot(x[:, 0] - 1.35, x[:, 2] - 0.95)
        inside = (r < 0.2 - 1e-4 * d) & (np.abs(x[:, 1]) < 1.0)
        assert not inside.any()
        touched += s["collision"]["contacts"]
        if s["collision"]["contacts"] == 0:
            assert np.abs(x - free.solve(a)).max() <= 1e-12 * d
    assert touched > 0


def test_scene_with_an_interior(cylinder):
    V0, V1, F = cylinder
    bar = morphkit.Obstacle.cylinder(0.2, 2.0, name="bar", keys=[(0, (1.35, 0.0, 0.95))])
    scene = morphkit.SceneBlend(V0, [V1], F, obstacles=[bar], interior="lattice")
    x = scene.solve(1.0)
    s = scene.last_stats
    assert s["solver"]["converged"] and s["collision"]["resolved"]
    assert s["collision"]["contacts"] > 0
    assert all(c["vertex"] < len(V0) for c in s["contacts"])
    r = np.hypot(x[:, 0] - 1.35, x[:, 2] - 0.95)
    assert not ((r < 0.2 - 1e-4 * diag(V0)) & (np.abs(x[:, 1]) < 1.0)).any()
    # Without obstacles it is the PhysicalBlend with the same interior, bit for bit.
    plain = morphkit.SceneBlend(V0, [V1], F, interior="lattice").solve(0.5)
    same = morphkit.PhysicalBlend(V0, [V1], F, interior="lattice").solve(0.5)
    assert np.array_equal(plain, same)
    # Its predictor is the volumetric blend's, on the surface: exact at the endpoints.
    preview = morphkit.SceneBlend(V0, [V1], F, interior="lattice").predictor()
    assert np.abs(preview.predict(0.0) - V0).max() < 1e-9
    assert np.abs(preview.predict(1.0) - V1).max() < 1e-9
    assert np.array_equal(
        preview.predict(0.5), morphkit.PhysicalBlend(V0, [V1], F, interior="lattice").predict(0.5)
    )
    with pytest.raises(morphkit.BlendError, match="anchor"):
        morphkit.SceneBlend(V0, [V1], F, anchor="1,2")


def test_scene_frames_on_threads_equal_single_solves(cylinder):
    V0, V1, F = cylinder
    ball = morphkit.Obstacle.sphere(
        0.3, keys=[(0, (1.2, -0.5, 0.9)), (3, (1.2, 0.5, 0.9))]
    )
    scene = morphkit.SceneBlend(V0, [V1], F, obstacles=[ball])
    alphas = [0.7, 0.8, 0.9, 1.0]
    one = np.stack([scene.solve(a, frame=k) for k, a in enumerate(alphas)])
    many = scene.solve_many(alphas, threads=2)
    assert many.shape == (4, len(V0), 3)
    assert np.array_equal(one, many)
    back = scene.solve_many(alphas[::-1], frames=[3, 2, 1, 0], threads=2)
    assert np.array_equal(one, back[::-1])
    with pytest.raises(morphkit.BlendError, match="frame numbers"):
        scene.solve_many(alphas, frames=[0, 1])


def test_far_obstacle_changes_nothing(cylinder):
    V0, V1, F = cylinder
    far = morphkit.Obstacle.sphere(0.1, keys=[(0, (50.0, 50.0, 50.0))])
    scene = morphkit.SceneBlend(V0, [V1], F, obstacles=[far])
    x = scene.solve(0.7)
    assert scene.last_stats["collision"]["contacts"] == 0
    assert np.abs(x - morphkit.PhysicalBlend(V0, [V1], F).solve(0.7)).max() <= 1e-12 * diag(V0)
    # The scene's predictor is the plain blend's (no obstacles, no pulls).
    plain = morphkit.PhysicalBlend(V0, [V1], F).predict(0.7)
    assert np.array_equal(scene.predictor().predict(0.7), plain)


def test_keyed_pull_follows_its_keys():
    V, F = grid(8)
    fixed = [i for i in range(len(V)) if V[i, 0] <= 1.0]
    tip = int(np.argmax(V[:, 0] + 1e-3 * V[:, 1]))
    keys = [(0.0, tuple(V[tip])), (10.0, tuple(V[tip] + [0, 0, 2.0]))]
    scene = morphkit.SceneBlend(V, [V.copy()], F, pulls=[(tip, keys)], fixed=fixed)
    for frame, lift in ((0.0, 0.0), (5.0, 1.0), (10.0, 2.0)):
        x = scene.solve(0.0, frame=frame)
        assert np.linalg.norm(x[tip] - (V[tip] + [0, 0, lift])) < 1e-3


def test_bad_scene_input():
    V, F = tube(6, 6)
    with pytest.raises(morphkit.BlendError):
        morphkit.Obstacle.sphere(-1.0)
    with pytest.raises(morphkit.BlendError):
        morphkit.Obstacle.sphere(1.0, keys=[(5, (0, 0, 0)), (1, (0, 0, 0))])  # out of order
    with pytest.raises(morphkit.BlendError):
        morphkit.Obstacle.mesh(V, F)  # an open tube has no inside
    with pytest.raises(morphkit.BlendError):
        morphkit.SceneBlend(V, [V], F, pulls=[(len(V) + 5, [(0.0, (0, 0, 0))])])
