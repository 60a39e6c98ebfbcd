"""examples/batch_dask.py on a 2-worker LocalCluster: every job kind runs, and a sequence split
by frame ranges across workers joins into the same file, byte for byte, as one process."""

import json
import pathlib
import sys

import numpy as np
import pytest

import morphkit
from conftest import bend, tube

ROOT = pathlib.Path(__file__).resolve().parents[2]
distributed = pytest.importorskip("distributed")
sys.path.insert(0, str(ROOT / "examples"))
import batch_dask  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_jobs_run_and_split_frames_join_exactly(tmp_path, client):
    V, F = tube(16, 10)
    morphkit.write(tmp_path / "rest.obj", V, F)
    morphkit.write(tmp_path / "bend.obj", bend(V, 2.0), F)
    for k, a in enumerate((0.5, 1.0)):
        morphkit.write(tmp_path / f"s{k}.obj", bend(V, a), F)
    (tmp_path / "markers.json").write_text(
        json.dumps({"pairs": [[i, i] for i in range(0, len(V), 17)]})
    )
    weights = [[a] for a in np.linspace(0.0, 1.0, 9)]
    jobs = [
        {"kind": "blend", "base": "rest.obj", "targets": ["bend.obj"], "weights": weights,
         "out": "split.pc2"},
        {"kind": "transfer", "source": "rest.obj", "frames": ["s0.obj", "s1.obj"],
         "target": "rest.obj", "markers": "markers.json", "out": "moved"},
        {"kind": "rig", "source": "rest.obj", "shapes": ["s0.obj", "s1.obj"],
         "target": "rest.obj", "markers": "markers.json", "out": "rig.glb"},
    ]
    (tmp_path / "jobs.json").write_text(json.dumps(jobs))
    outs = batch_dask.run(tmp_path / "jobs.json", client, chunk=2)
    assert [o.name for o in outs] == ["split.pc2", "moved", "rig.glb"]
    # Tasks were spread over both workers.
    who = client.run(lambda dask_worker: len(getattr(dask_worker, "_morphkit_cache", {})))
    assert sum(1 for n in who.values() if n > 0) == 2, who

    # One process, no Dask: the same bytes.
    blend = morphkit.PhysicalBlend(V, [bend(V, 2.0)], F)
    morphkit.write_animation(tmp_path / "one.pc2", blend.solve_many(weights), F)
    assert (tmp_path / "split.pc2").read_bytes() == (tmp_path / "one.pc2").read_bytes()

    _, _, T, names = morphkit.read_morphs(tmp_path / "rig.glb")
    assert names == ["s0", "s1"] and T.shape == (2, len(V), 3)
    frames, _, _ = morphkit.read_animation(tmp_path / "moved")
    assert frames.shape == (2, len(V), 3)
