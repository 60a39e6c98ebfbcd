"""Shared fixtures: real data through MORPHKIT_DATA (skipped when unset, an error when set and
a file is missing), the CLI binary through MORPHKIT_BIN, and small generated meshes."""

import os
import pathlib
import subprocess

import numpy as np
import pytest


def data_file(rel):
    root = os.environ.get("MORPHKIT_DATA")
    if not root:
        pytest.skip("MORPHKIT_DATA is not set")
    p = pathlib.Path(root) / rel
    if not p.exists():
        raise FileNotFoundError(f"MORPHKIT_DATA is set but {p} is missing")
    return p


@pytest.fixture
def data():
    return data_file


@pytest.fixture
def cli():
    """Runs the `morphkit` binary of the same build; skipped when it was not built."""
    exe = os.environ.get("MORPHKIT_BIN")
    if not exe:
        pytest.skip("MORPHKIT_BIN is not set")

    def run(*args):
        r = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r

    return run


def grid(n=8):
    """An n × n grid of unit squares in the xy plane, two triangles each."""
    xs, ys = np.meshgrid(np.arange(n + 1, dtype=float), np.arange(n + 1, dtype=float))
    V = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    F = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            F += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return V, np.array(F, dtype=np.int64)


def tube(rings=24, around=12, length=6.0, radius=0.5):
    """An open tube along x."""
    V = []
    for r in range(rings + 1):
        for k in range(around):
            t = 2 * np.pi * k / around
            V.append([length * r / rings, radius * np.cos(t), radius * np.sin(t)])
    F = []
    for r in range(rings):
        for k in range(around):
            a, b = r * around + k, r * around + (k + 1) % around
            F += [[a, b, b + around], [a, b + around, a + around]]
    return np.array(V), np.array(F, dtype=np.int64)


def bend(V, angle):
    """Bends a tube along x about the z axis by `angle` over its length (x ≥ 0 bends)."""
    L = V[:, 0].max()
    R = L / angle
    th = V[:, 0] / L * angle
    out = V.copy()
    out[:, 0] = (R - V[:, 1]) * np.sin(th)
    out[:, 1] = R - (R - V[:, 1]) * np.cos(th)
    return out


def diag(V):
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def capped_tube(rings=16, around=12, length=6.0, radius=0.5):
    """A closed tube along x (end caps fanned around a centre vertex), outward-oriented."""
    V, F = tube(rings, around, length, radius)
    n = len(V)
    V = np.vstack([V, [[0.0, 0.0, 0.0], [length, 0.0, 0.0]]])
    caps = []
    last = rings * around
    for k in range(around):
        k1 = (k + 1) % around
        caps.append([n, k1, k])
        caps.append([n + 1, last + k, last + k1])
    F = np.vstack([F, np.array(caps)])
    return V, F
