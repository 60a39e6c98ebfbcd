"""One PhysicalBlend or SceneBlend shared by several Python threads: solves queue (none fails
with "Already borrowed"), each returns what it returns alone, bit for bit, and the properties
answer while a solve runs."""

import threading

import numpy as np
import pytest

import morphkit
from conftest import bend, tube

ALPHAS = [0.15, 0.35, 0.6, 0.85]


def make(kind, V, B, F):
    if kind == "blend":
        return morphkit.PhysicalBlend(V, [B], F)
    ball = morphkit.Obstacle.sphere(0.4, keys=[(0, (3.0, 1.2, 0.0)), (3, (3.0, 0.6, 0.0))])
    return morphkit.SceneBlend(V, [B], F, obstacles=[ball])


def solve_one(solver, kind, k):
    if kind == "blend":
        return solver.solve(ALPHAS[k])
    return solver.solve(ALPHAS[k], frame=k)


def run_threads(work, n):
    """Runs work(i) on n threads started together; returns the exceptions they raised."""
    barrier = threading.Barrier(n)
    errors = []

    def body(i):
        try:
            barrier.wait()
            work(i)
        except BaseException as e:  # noqa: BLE001 (reported below)
            errors.append(e)

    ts = [threading.Thread(target=body, args=(i,)) for i in range(n)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return errors


@pytest.mark.parametrize("kind", ["blend", "scene"])
def test_four_threads_share_one_solver(kind):
    V, F = tube()
    B = bend(V, 2.0)
    # The sequential results, from a solver of its own.
    ref = make(kind, V, B, F)
    one = [solve_one(ref, kind, k) for k in range(4)]
    many = ref.solve_many([[a] for a in ALPHAS], threads=2)
    assert np.array_equal(np.stack(one), many)

    shared = make(kind, V, B, F)
    out = {}

    def work(i):
        for rep in range(3):
            k = (i + rep) % 4
            out[i, rep] = solve_one(shared, kind, k)
            assert shared.last_stats is not None
        out[i, "many"] = shared.solve_many([[a] for a in ALPHAS], threads=1 + i % 2)

    errors = run_threads(work, 4)
    assert not errors, errors
    for i in range(4):
        for rep in range(3):
            assert np.array_equal(out[i, rep], one[(i + rep) % 4]), (i, rep)
        assert np.array_equal(out[i, "many"], many), i


@pytest.mark.parametrize("kind", ["blend", "scene"])
def test_properties_answer_while_a_solve_runs(kind):
    V, F = tube(rings=40, around=20)
    B = bend(V, 2.0)
    solver = make(kind, V, B, F)
    solver.solve(0.4)
    first = solver.last_stats
    preview = solver.predictor().predict(0.5)
    rows = [[a] for a in np.linspace(0.05, 0.95, 60)]
    started = threading.Event()
    errors = []

    def work():
        started.set()
        try:
            solver.solve_many(rows)
        except BaseException as e:  # noqa: BLE001 (reported below)
            errors.append(e)

    t = threading.Thread(target=work)
    t.start()
    started.wait()
    reads = 0
    while t.is_alive():
        stats = solver.last_stats
        assert stats is not None and stats.keys() == first.keys()
        assert np.array_equal(solver.predictor().predict(0.5), preview)
        if kind == "blend":
            assert solver.num_targets == 1
            assert solver.summary["vertices"] == len(V)
            assert np.array_equal(solver.predict(0.5), preview)
        reads += 1
    t.join()
    assert not errors, errors
    assert reads > 0
