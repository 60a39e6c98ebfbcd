"""morphkit: physically plausible, reusable mesh animation.

A thin Python client of the morphkit Rust library. Arrays follow libigl's conventions:
vertices ``V`` as ``(n, 3) float64``, triangles ``F`` as ``(m, 3)`` integers, animations as
``(k, n, 3) float64``. Errors are :class:`MorphkitError` (a :class:`ValueError`); file errors
are also :class:`OSError`. Solves release the GIL; solvers may be shared between threads (their
solves queue), and batches (``solve_many``, ``transfer_many``) honour Ctrl-C between frames.

>>> import morphkit
>>> V0, F = morphkit.read("rest.obj")
>>> V1, _ = morphkit.read("bend.obj")
>>> blend = morphkit.PhysicalBlend(V0, [V1], F)
>>> half = blend.solve(0.5)
"""

from ._errors import BlendError, FileError, MeshError, MorphkitError, TransferError
from ._morphkit import (
    BakedRig,
    Correspondence,
    Obstacle,
    Partitions,
    PhysicalBlend,
    Predictor,
    RigTransfer,
    SceneBlend,
    Transfer,
    __version__,
    continuity,
    flexibility,
    geodesic_distance,
    metrics,
    read,
    read_animation,
    read_morphs,
    read_rig,
    rig_defaults,
    synthesize,
    transfer_defaults,
    write,
    write_animation,
    write_morphs,
    write_rig,
)

__all__ = [
    "BakedRig",
    "BlendError",
    "Correspondence",
    "FileError",
    "MeshError",
    "MorphkitError",
    "Obstacle",
    "Partitions",
    "PhysicalBlend",
    "Predictor",
    "RigTransfer",
    "SceneBlend",
    "Transfer",
    "TransferError",
    "__version__",
    "continuity",
    "flexibility",
    "geodesic_distance",
    "metrics",
    "read",
    "read_animation",
    "read_rig",
    "rig_defaults",
    "read_morphs",
    "synthesize",
    "transfer_defaults",
    "write",
    "write_animation",
    "write_morphs",
    "write_rig",
]
