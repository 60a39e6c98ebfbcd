"""Type stubs of the compiled module (see the docstrings for details).

Conventions: face arrays may have any integer dtype (signed or unsigned, 8 to 64 bits; negative
indices are refused). Integer arguments (counts such as ``threads``, indices such as
``sources``) accept any integer, numpy's included: an integer outside the allowed range raises
the module's error (a ``ValueError``) naming the argument, the value and the range; a value
that is not an integer raises ``TypeError`` naming the argument.

Thread safety: every class may be shared between threads. ``PhysicalBlend`` and ``SceneBlend``
run one solve at a time, with the GIL released: concurrent calls wait for each other (they do
not fail), and each returns what it would return alone. Their properties, ``predict`` and
``predictor`` answer at once while a solve runs. ``solve_many`` and ``transfer_many`` honour
Ctrl-C (``KeyboardInterrupt``) between frames.
"""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, os.PathLike]
Vertices = npt.NDArray[np.float64]  # (n, 3)
Faces = npt.NDArray[np.int64]  # (m, 3); as input, any integer dtype
Frames = npt.NDArray[np.float64]  # (k, n, 3)
ArrayLike = npt.ArrayLike

def read(path: PathLike) -> Tuple[Vertices, Faces]: ...
def write(path: PathLike, v: ArrayLike, f: ArrayLike) -> None: ...
def read_morphs(path: PathLike) -> Tuple[Vertices, Faces, Frames, List[str]]: ...
def write_morphs(
    path: PathLike,
    v: ArrayLike,
    f: ArrayLike,
    targets: Union[ArrayLike, Sequence[ArrayLike]],
    names: Optional[Sequence[str]] = None,
) -> None: ...
def read_animation(
    path: PathLike, reference: Optional[PathLike] = None
) -> Tuple[Frames, Faces, List[str]]: ...
def write_animation(
    path: PathLike,
    frames: Union[ArrayLike, Sequence[ArrayLike]],
    f: Optional[ArrayLike] = None,
    fps: float = 24.0,
    template: Optional[PathLike] = None,
    clip: Optional[str] = None,
    times: Optional[Sequence[float]] = None,
    mesh: Optional[str] = None,
    max_targets: int = 200,
    clip_tolerance: Optional[float] = None,
    per_frame_targets: bool = False,
    quantize: bool = False,
    meshopt: bool = False,
) -> None: ...
def read_rig(
    path: PathLike, mesh: Optional[str] = None, animation: Optional[str] = None
) -> Dict[str, Any]: ...
def write_rig(
    path: PathLike,
    template: PathLike,
    targets: Union[ArrayLike, Sequence[ArrayLike]],
    names: Sequence[str],
    base: Optional[ArrayLike] = None,
    mesh: Optional[str] = None,
    max_targets: int = 200,
) -> None: ...
def metrics(v_rest: ArrayLike, v: ArrayLike, f: ArrayLike) -> Dict[str, Any]: ...
def continuity(
    frames: ArrayLike, linear: ArrayLike, bound: float = 4.0
) -> Dict[str, Any]: ...


class BakedRig:
    """Physical correctives baked into in-between and combination shapes (PhysicalBlend.bake)."""

    def evaluate(self, weights: Union[float, Sequence[float]]) -> Vertices: ...
    def combination_weights(self, weights: Union[float, Sequence[float]]) -> List[float]: ...
    def shape_weights(self, weights: Union[float, Sequence[float]]) -> List[float]: ...
    def inbetween(self, target: int, k: int) -> Vertices: ...
    def combination(self, k: int, level: int = 0) -> Vertices: ...
    @property
    def base(self) -> Vertices: ...
    @property
    def inbetween_weights(self) -> List[List[float]]: ...
    @property
    def combinations(self) -> List[Tuple[int, int]]: ...
    @property
    def combination_levels(self) -> List[List[float]]: ...
    @property
    def damping(self) -> float: ...
    @property
    def num_shapes(self) -> int: ...

class PhysicalBlend:
    """Thread-safe: solves run one at a time (GIL released; concurrent calls queue), while
    ``num_targets``, ``summary``, ``last_stats``, ``predict`` and ``predictor`` answer at once."""

    def __init__(
        self,
        base: ArrayLike,
        targets: Union[ArrayLike, Sequence[ArrayLike]],
        faces: ArrayLike,
        *,
        fixed: Union[None, str, Sequence[int]] = None,
        hinge_weight: Optional[float] = None,
        tether: Optional[float] = None,
        kinematic_stretch: Optional[float] = None,
        thin_band_rings: Optional[int] = None,  # >= 0
        gradient_tolerance: Optional[float] = None,
        max_newton_iterations: Optional[int] = None,  # >= 0
        sampled_start: bool = True,
        continuation_steps: Optional[int] = None,  # 0–64; frames solved along their ray
        interior: Optional[str] = None,
        anchor: Optional[str] = None,
        weld: bool = True,  # split seam/hard-edge vertices are one vertex for the solve
    ) -> None: ...
    def solve(
        self,
        weights: Union[float, Sequence[float]],
        *,
        convex: bool = False,
        pulls: Union[
            None, Mapping[int, Sequence[float]], Sequence[Tuple[int, Sequence[float]]]
        ] = None,
        interactive: bool = False,  # the prepared space's fast shape; see prepare_interactive
        refine: int = 0,  # >= 0; projected-Newton steps after an interactive solve
    ) -> Vertices: ...
    def prepare_interactive(
        self,
        *,
        threads: int = 1,  # >= 1; the result does not depend on it
        cache: Optional[PathLike] = None,  # read when it holds this rig's preparation, else written
    ) -> Dict[str, Any]: ...
    def bake(
        self,
        *,
        inbetweens: int = 7,  # in-betweens per target at k / (inbetweens + 1)
        pair_tolerance: float = 1e-4,  # fraction of the diagonal
        max_pairs: int = 120,
        damping: float = 0.0,
        pair_samples: Optional[Sequence[float]] = None,  # default [0.5, 1.0]
        threads: int = 1,
        inbetween_tolerance: float = 1e-3,  # fraction of the diagonal; 0: the regular grid
        max_refined: int = 64,
    ) -> "BakedRig": ...
    def solve_many(
        self,
        weights: Sequence[Union[float, Sequence[float]]],
        *,
        convex: bool = False,
        threads: int = 1,  # >= 1; frames are solved `threads` at a time, Ctrl-C between them
    ) -> Frames: ...
    def predict(self, weights: Union[float, Sequence[float]], *, convex: bool = False) -> Vertices: ...
    def predictor(self) -> "Predictor": ...
    @property
    def last_stats(self) -> Optional[Dict[str, Any]]: ...
    @property
    def summary(self) -> Dict[str, Any]: ...
    @property
    def num_targets(self) -> int: ...
    @property
    def welded_vertices(self) -> int: ...  # input vertices welded into others for the solve

class Predictor:
    def predict(self, weights: Union[float, Sequence[float]], *, convex: bool = False) -> Vertices: ...

class Correspondence:
    @staticmethod
    def from_markers(
        vs: ArrayLike,
        fs: ArrayLike,
        vt: ArrayLike,
        ft: ArrayLike,
        markers: Union[PathLike, Sequence[Sequence[int]], ArrayLike],
        *,
        refine: Optional[bool] = None,  # None: the library's default (refined)
        weld: bool = True,  # split seam vertices are one vertex while warping
    ) -> "Correspondence": ...
    @staticmethod
    def identity(v: ArrayLike, f: ArrayLike) -> "Correspondence": ...
    @staticmethod
    def load(path: PathLike) -> "Correspondence": ...
    def save(self, path: PathLike) -> None: ...
    @property
    def matches(self) -> List[List[int]]: ...
    @property
    def marker_residuals(self) -> List[Dict[str, Any]]: ...
    @property
    def normal_violations(self) -> List[int]: ...
    @property
    def refined(self) -> bool: ...
    @property
    def warped(self) -> Optional[Tuple[Vertices, Vertices]]: ...

class Transfer:
    def __init__(
        self,
        vs: ArrayLike,
        fs: ArrayLike,
        vt: ArrayLike,
        ft: ArrayLike,
        correspondence: Correspondence,
        *,
        # None: the library's default, as `morphkit transfer` without flags
        # (transfer_defaults()).
        combine: Optional[str] = None,  # "inverse-distance" | "mean" | "nearest"
        translation: Optional[str] = None,  # "follow" | "fixed"
        local_stretch: Optional[bool] = None,
        area_weighted: Optional[bool] = None,
        fold_guard: Optional[bool] = None,
        weld: bool = True,  # the target's split seam vertices are one vertex for the solve
    ) -> None: ...
    @property
    def options(self) -> Dict[str, Any]: ...
    def transfer(self, frame: ArrayLike) -> Vertices: ...
    def transfer_many(self, frames: Union[ArrayLike, Sequence[ArrayLike]]) -> Frames: ...

def flexibility(v: ArrayLike, f: ArrayLike, frames: Union[ArrayLike, Sequence[ArrayLike]]) -> npt.NDArray[np.float64]: ...
def geodesic_distance(
    v: ArrayLike, f: ArrayLike, sources: Union[Sequence[int], ArrayLike]
) -> npt.NDArray[np.float64]: ...
def synthesize(recipe: PathLike) -> Tuple[Frames, Faces]: ...
def transfer_defaults() -> Dict[str, Any]: ...
def rig_defaults() -> Dict[str, Any]: ...  # morphkit rig's: refine (False), combine, local_stretch, ...

class Partitions:
    def __init__(
        self,
        v: ArrayLike,
        f: ArrayLike,
        flexibility: Union[Sequence[float], ArrayLike],  # (m,): one finite value >= 0 per triangle
        *,
        gamma: float = 0.1,
    ) -> None: ...
    @property
    def labels(self) -> npt.NDArray[np.int64]: ...
    @property
    def stiff(self) -> npt.NDArray[np.bool_]: ...
    @property
    def num_partitions(self) -> int: ...
    def refine(
        self,
        *,
        triangles: Union[None, Sequence[int], ArrayLike] = None,
        vertices: Union[None, Sequence[int], ArrayLike] = None,
    ) -> npt.NDArray[np.bool_]: ...
    def blend_weights(self, selection: ArrayLike, *, kappa: float = 1e4) -> npt.NDArray[np.float64]: ...
    def edit_pose(self, scribble: ArrayLike, axis: Sequence[float], angle: float) -> Vertices: ...

Key = Union[Tuple[float, Sequence[float]], Tuple[float, Sequence[float], Sequence[float]]]

class Obstacle:
    @staticmethod
    def sphere(radius: float, *, name: str = "sphere", keys: Optional[Sequence[Key]] = None) -> "Obstacle": ...
    @staticmethod
    def box(size: Sequence[float], *, name: str = "box", keys: Optional[Sequence[Key]] = None) -> "Obstacle": ...
    @staticmethod
    def cylinder(
        radius: float, height: float, *, name: str = "cylinder", keys: Optional[Sequence[Key]] = None
    ) -> "Obstacle": ...
    @staticmethod
    def mesh(v: ArrayLike, f: ArrayLike, *, name: str = "mesh", keys: Optional[Sequence[Key]] = None) -> "Obstacle": ...
    @property
    def name(self) -> str: ...

class SceneBlend:
    """Thread-safe as :class:`PhysicalBlend`: solves queue; ``last_stats`` and ``predictor``
    answer while a solve runs."""

    def __init__(
        self,
        base: ArrayLike,
        targets: Union[ArrayLike, Sequence[ArrayLike]],
        faces: ArrayLike,
        *,
        obstacles: Sequence[Obstacle] = (),
        pulls: Sequence[Tuple[int, Sequence[Tuple[float, Sequence[float]]]]] = (),
        fixed: Union[None, str, Sequence[int]] = None,
        hinge_weight: Optional[float] = None,
        tolerance: float = 1e-4,
        max_rounds: int = 10,  # >= 0
        interior: Optional[str] = None,
        anchor: Optional[str] = None,
        weld: bool = True,  # as PhysicalBlend: split seam vertices are one vertex
    ) -> None: ...
    def solve(self, weights: Union[float, Sequence[float]], *, frame: float = 0.0, convex: bool = False) -> Vertices: ...
    def solve_many(
        self,
        weights: Sequence[Union[float, Sequence[float]]],
        *,
        frames: Optional[Sequence[float]] = None,
        convex: bool = False,
        threads: int = 1,  # >= 1; frames are solved `threads` at a time, Ctrl-C between them
    ) -> np.ndarray: ...
    def predictor(self) -> "Predictor": ...
    @property
    def last_stats(self) -> Optional[Dict[str, Any]]: ...

class RigTransfer:
    def __init__(
        self,
        vs: ArrayLike,
        fs: ArrayLike,
        vt: ArrayLike,
        ft: ArrayLike,
        correspondence: Correspondence,
        *,
        combine: Optional[str] = None,  # None: the library's default
        weld: bool = True,  # the target's split seam vertices are one vertex for the solve
    ) -> None: ...
    def transfer(self, shape: ArrayLike) -> Vertices: ...
    def transfer_many(self, shapes: Union[ArrayLike, Sequence[ArrayLike]]) -> Frames: ...
