"""Batch jobs on Dask: blends of weight animations, animation transfers and rig transfers,
spread over a cluster with no coordination of morphkit's own.

    python examples/batch_dask.py jobs.json                      # a LocalCluster (2 workers)
    python examples/batch_dask.py jobs.json --scheduler tcp://host:8786
    python examples/batch_dask.py jobs.json --chunk 12           # split sequences by frames

jobs.json is a list of jobs; paths are relative to the file:

    [{"kind": "blend", "base": "rest.obj", "targets": ["bend.obj"],
      "weights": [[0.0], [0.1], ...], "out": "bend.pc2"},
     {"kind": "transfer", "source": "horse.obj", "frames": ["h01.obj", ...],
      "target": "camel.obj", "markers": "markers.json", "out": "camel.pc2"},
     {"kind": "rig", "source": "neutral.obj", "shapes": ["jawOpen.obj", ...],
      "target": "head.obj", "markers": "markers.json", "out": "head-rig.glb"}]

Each frame depends only on its weights (the physical blend is canonical), so a long sequence
is cut into frame ranges (`--chunk`), solved on any worker and joined in order; the joined
output is the one-process output. Each worker builds the prefactored solver (PhysicalBlend,
Transfer) once per (meshes, options) and keeps it for every later task that needs it.
"""

import argparse
import json
import pathlib

import numpy as np

import morphkit


def _cache():
    """This worker's solver cache (a plain dict outside a Dask worker)."""
    try:
        from distributed import get_worker

        w = get_worker()
    except (ImportError, ValueError):
        return _cache.local
    if not hasattr(w, "_morphkit_cache"):
        w._morphkit_cache = {}
    return w._morphkit_cache


_cache.local = {}


def _blend_solver(base, targets):
    key = ("blend", base, tuple(targets))
    c = _cache()
    if key not in c:
        V0, F = morphkit.read(base)
        c[key] = (morphkit.PhysicalBlend(V0, [morphkit.read(t)[0] for t in targets], F), F)
    return c[key]


def _transfer_solver(source, target, markers, rig):
    key = ("rig" if rig else "transfer", source, target, markers)
    c = _cache()
    if key not in c:
        VS, FS = morphkit.read(source)
        VT, FT = morphkit.read(target)
        corr = morphkit.Correspondence.from_markers(VS, FS, VT, FT, markers)
        kind = morphkit.RigTransfer if rig else morphkit.Transfer  # a rig has no root motion
        c[key] = (kind(VS, FS, VT, FT, corr), FT)
    return c[key]


def blend_range(base, targets, weights):
    """Frames of a blend for `weights` (a list of weight vectors): (k, n, 3)."""
    blend, _ = _blend_solver(base, targets)
    return blend.solve_many(weights)


def transfer_range(source, target, markers, frames, rig=False):
    """The given source frame (or rig shape) files transferred onto the target: (k, n_t, 3)."""
    tr, _ = _transfer_solver(source, target, markers, rig)
    return tr.transfer_many([morphkit.read(f)[0] for f in frames])


def _chunks(items, size):
    return [items[i : i + size] for i in range(0, len(items), size)] if size else [items]


def submit(client, job, root, chunk):
    """Submits one job's tasks; returns (job, futures in frame order)."""
    p = lambda x: str((root / x).resolve())  # noqa: E731
    kind = job["kind"]
    if kind == "blend":
        base, targets = p(job["base"]), [p(t) for t in job["targets"]]
        futs = [
            client.submit(blend_range, base, targets, w, pure=False)
            for w in _chunks(job["weights"], chunk)
        ]
    elif kind in ("transfer", "rig"):
        frames = [p(f) for f in job["frames" if kind == "transfer" else "shapes"]]
        futs = [
            client.submit(
                transfer_range, p(job["source"]), p(job["target"]), p(job["markers"]), fr,
                kind == "rig", pure=False,
            )
            for fr in _chunks(frames, chunk)
        ]
    else:
        raise ValueError(f"job {job!r}: unknown kind {kind!r} (blend, transfer or rig)")
    return futs


def write(job, root, frames):
    """Writes one job's joined frames (atomically, through the module's writers)."""
    out = root / job["out"]
    kind = job["kind"]
    if kind == "blend":
        _, F = morphkit.read(root / job["base"])
        morphkit.write_animation(out, frames, F)
    elif kind == "transfer":
        _, F = morphkit.read(root / job["target"])
        morphkit.write_animation(out, frames, F)
    else:
        V, F = morphkit.read(root / job["target"])
        names = [pathlib.Path(s).name.split(".")[0] for s in job["shapes"]]
        morphkit.write_morphs(out, V, F, frames, names=names)
    return out


def run(jobs_file, client, chunk=0):
    """Runs every job of `jobs_file` on `client`; returns the written paths."""
    root = pathlib.Path(jobs_file).resolve().parent
    jobs = json.loads(pathlib.Path(jobs_file).read_text())
    pending = [(job, submit(client, job, root, chunk)) for job in jobs]
    outs = []
    for job, futs in pending:
        frames = np.concatenate(client.gather(futs), axis=0)
        outs.append(write(job, root, frames))
    return outs


def main():
    ap = argparse.ArgumentParser(description="Run morphkit batch jobs on Dask")
    ap.add_argument("jobs", help="jobs JSON file")
    ap.add_argument("--scheduler", help="scheduler address (default: a LocalCluster)")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster workers")
    ap.add_argument("--chunk", type=int, default=0, help="frames per task (0: one task a job)")
    a = ap.parse_args()
    from distributed import Client, LocalCluster

    if a.scheduler:
        client = Client(a.scheduler)
    else:
        client = Client(LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True))
    with client:
        for out in run(a.jobs, client, a.chunk):
            print(out)


if __name__ == "__main__":
    main()
