"""Overhead of the Python module over the library's own time.

    MORPHKIT_DATA=../shared/data python python/examples/bench_overhead.py

- Transfer.transfer_many on horse → camel (10 poses): the Python call's wall time against the
  library's own per-frame solves, timed in the same process through Transfer.transfer on
  frames already converted (the remaining difference is array conversion).
- PhysicalBlend.solve on horse reference ↔ horse-05 at α = 0.5: the call's wall time against
  the solve time the library reports in last_stats["seconds"].
"""

import os
import pathlib
import time

import numpy as np

import morphkit

root = pathlib.Path(os.environ["MORPHKIT_DATA"])
hc = root / "sumner-horse-camel"
VS, FS = morphkit.read(hc / "horse-reference.obj.gz")
VT, FT = morphkit.read(hc / "camel-reference.obj.gz")
poses = np.stack([morphkit.read(hc / f"horse-{k:02}.obj.gz")[0] for k in range(1, 11)])

t0 = time.perf_counter()
corr = morphkit.Correspondence.from_markers(VS, FS, VT, FT, hc / "markers-horse-camel.json")
t1 = time.perf_counter()
tr = morphkit.Transfer(VS, FS, VT, FT, corr)
t2 = time.perf_counter()
best_many = min(
    (lambda s: (tr.transfer_many(poses), time.perf_counter() - s)[1])(time.perf_counter())
    for _ in range(5)
)
best_single = min(
    (lambda s: ([tr.transfer(p) for p in poses], time.perf_counter() - s)[1])(time.perf_counter())
    for _ in range(5)
)
print(f"correspondence {t1 - t0:.3f} s, transfer set-up {t2 - t1:.3f} s")
print(f"transfer_many, 10 frames: {best_many * 1e3:.1f} ms ({best_many * 1e2:.2f} ms/frame)")
print(f"10 x transfer:            {best_single * 1e3:.1f} ms")

V1, _ = morphkit.read(hc / "horse-05.obj.gz")
blend = morphkit.PhysicalBlend(VS, [V1], FS)
walls, libs = [], []
for _ in range(3):
    s = time.perf_counter()
    blend.solve(0.5)
    walls.append(time.perf_counter() - s)
    libs.append(blend.last_stats["seconds"])
w, lib = min(walls), min(libs)
print(f"PhysicalBlend.solve(0.5): call {w * 1e3:.1f} ms, library {lib * 1e3:.1f} ms, "
      f"overhead {100 * (w - lib) / lib:.2f}%")
