"""Ctrl-C during PhysicalBlend.solve_many, SceneBlend.solve_many and Transfer.transfer_many:
KeyboardInterrupt comes after the frames being solved, not at the end of the batch. Each case
runs in a child interpreter that gets a real SIGINT."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

CHILD = r"""
import json, signal, sys, time
sys.path.insert(0, sys.argv[1])
signal.signal(signal.SIGINT, signal.default_int_handler)  # also when started with SIGINT ignored
import numpy as np
import morphkit
from conftest import bend, tube

kind, threads = sys.argv[2], int(sys.argv[3])
V, F = tube(rings=40, around=20)
B = bend(V, 2.0)
if kind == "transfer":
    # local_stretch: ~2 ms a frame, so that the batch's arrays stay small
    identity = morphkit.Correspondence.identity(V, F)
    transfer = morphkit.Transfer(V, F, V, F, identity, local_stretch=True)
    inputs = lambda alphas: np.stack([V + a * (B - V) for a in alphas])
    run = transfer.transfer_many
else:
    solver = morphkit.PhysicalBlend(V, [B], F) if kind == "blend" else morphkit.SceneBlend(V, [B], F)
    solver.solve(0.4)  # the sampled start's fields, computed once
    inputs = lambda alphas: [[a] for a in alphas]
    run = lambda rows: solver.solve_many(rows, threads=threads)
few = inputs((0.11, 0.23, 0.37, 0.61, 0.67, 0.83))
t = time.perf_counter()
run(few)
guess = (time.perf_counter() - t) / len(few)
# At least 60 frames, for a batch of 1-3 s on this machine, now (the guess from a few frames
# runs high); the batch is timed once whole, then solved again and interrupted.
n = max(60, int(3.0 / guess))
batch_inputs = inputs(np.linspace(0.05, 0.95, n))
t = time.perf_counter()
run(batch_inputs)
batch = time.perf_counter() - t
try:
    print(json.dumps({"batch": batch}), flush=True)
    t = time.perf_counter()
    run(batch_inputs)
    outcome = "finished"
except KeyboardInterrupt:
    outcome = "interrupted"
elapsed = time.perf_counter() - t
print(json.dumps({"outcome": outcome, "elapsed": elapsed, "batch": batch, "frames": n}), flush=True)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process")
@pytest.mark.parametrize(
    "kind,threads", [("blend", 1), ("blend", 2), ("scene", 2), ("transfer", 1)]
)
def test_ctrl_c_interrupts_solve_many(kind, threads):
    here = os.path.dirname(os.path.abspath(__file__))
    p = subprocess.Popen(
        [sys.executable, "-c", CHILD, here, kind, str(threads)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        ready = json.loads(p.stdout.readline())
        # Well inside the batch: past its start, and long before its end.
        time.sleep(0.1 * ready["batch"])
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["outcome"] == "interrupted", result
    # The whole batch took `batch` seconds when the child timed it uninterrupted; the interrupt
    # came after the delay plus at most one chunk of frames.
    assert result["elapsed"] < 0.5 * result["batch"], result


PREPARE = r"""
import json, os, signal, sys, time
sys.path.insert(0, sys.argv[1])
signal.signal(signal.SIGINT, signal.default_int_handler)
import numpy as np
import morphkit
from conftest import bend, tube

cache, threads = sys.argv[2], int(sys.argv[3])
# 6 targets: 42 single-target and 30 pair snapshots, then 120 checks (about 1 s released)
V, F = tube(rings=40, around=20)
targets = [bend(V, a) for a in (0.4, 0.8, 1.2, 1.6, 2.0, 2.4)]
t = time.perf_counter()
morphkit.PhysicalBlend(V, targets, F).prepare_interactive(threads=threads)
full = time.perf_counter() - t
solver = morphkit.PhysicalBlend(V, targets, F)
report = None
try:
    print(json.dumps({"full": full}), flush=True)
    t = time.perf_counter()
    report = solver.prepare_interactive(threads=threads, cache=cache)
    outcome = "finished"
except KeyboardInterrupt:
    outcome = "interrupted"
elapsed = time.perf_counter() - t
print(json.dumps({"outcome": outcome, "elapsed": elapsed, "full": full, "returned": report is not None,
                  "cache": os.path.exists(cache)}), flush=True)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process")
@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_stops_prepare_interactive_between_snapshots(tmp_path, threads):
    """Ctrl-C during prepare_interactive raises KeyboardInterrupt inside the call, after the
    snapshot solves running then, not once the whole preparation is done; no cache is written
    (issue 55)."""
    here = os.path.dirname(os.path.abspath(__file__))
    cache = tmp_path / "rig.mkinter"
    p = subprocess.Popen(
        [sys.executable, "-c", PREPARE, here, str(cache), str(threads)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        ready = json.loads(p.stdout.readline())
        time.sleep(0.1 * ready["full"])
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=300)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["outcome"] == "interrupted" and not result["returned"], result
    assert not result["cache"] and not cache.exists(), result
    # The whole preparation took `full` seconds when the child timed it uninterrupted; the
    # interrupt came after a tenth of it plus the snapshot solves running then.
    assert result["elapsed"] < 0.6 * result["full"], result
