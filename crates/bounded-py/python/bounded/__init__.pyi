"""BoundED: sharp edges and boundaries in 3D point clouds, from the point positions alone.

Type stubs of the package (the native module ``bounded._bounded``, re-exported); the
docstrings of the module itself say the same at run time. ``bounded.distributed`` is Python.
"""

import os
from typing import Callable, Final, Literal, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: Final[str]

NON_EDGE: Final[int]
"""Class code of a point on no edge (0)."""
SHARP: Final[int]
"""Class code of a point on a sharp edge, a crease or corner (1)."""
BOUNDARY: Final[int]
"""Class code of a point on a boundary, the border of an open surface (2)."""
CLASS_NAMES: Final[tuple[str, str, str]]
"""The class names in code order: ("non-edge", "sharp", "boundary")."""

_Path = Union[str, os.PathLike[str]]
_Positions = npt.NDArray[Union[np.float32, np.float64]]
_Group = Literal["sigma", "sigma_u", "sigma_l", "d", "s", "c", "h"]

class Model:
    """A BoundED model: its networks (one or two stages), the scales and features it was
    trained with."""

    @staticmethod
    def embedded(name: Literal["row", "band"] = "row") -> Model:
        """A model built into the package: ``"row"`` (the default) calls one row of points
        along each crease, as the PCEDNet and ABC clouds are labelled; ``"band"`` calls a band
        3 spacings wide, as feature curves are often labelled. Both have two stages at 16
        scales from 128 down to 10 neighbours, trained on generated clouds only.

        Raises ``ValueError`` for another name."""
    @staticmethod
    def load(path: _Path) -> Model:
        """Reads a ``.bmodel`` file written by ``bounded train``.

        Raises ``FileNotFoundError`` (or another ``OSError``) when the file cannot be read,
        ``ValueError`` when it is not a model this build can run."""
    @property
    def scales(self) -> list[int]:
        """The neighbourhood sizes the model was trained with, largest first."""
    @property
    def feature_names(self) -> list[str]:
        """The names of the features of one scale."""
    @property
    def sensitivity(self) -> float | None:
        """The decision the model records (chosen on validation clouds when it was trained):
        a sensitivity, or None for the most probable class."""
    @property
    def stages(self) -> int:
        """1, or 2 for an auto-context model."""

class Detection:
    """The result of ``detect``: a class and three class probabilities per point, in input
    order."""

    NON_EDGE: Final[int]
    SHARP: Final[int]
    BOUNDARY: Final[int]
    @property
    def classes(self) -> npt.NDArray[np.uint8]:
        """Class code per point, shape (n,): ``NON_EDGE`` 0, ``SHARP`` 1, ``BOUNDARY`` 2."""
    @property
    def probabilities(self) -> npt.NDArray[np.float32]:
        """Probabilities per point, shape (n, 3): non-edge, sharp edge, boundary."""
    def __len__(self) -> int: ...

def detect(
    xyz: _Positions,
    *,
    model: Union[Model, _Path, None] = None,
    scales: Sequence[int] | None = None,
    sensitivity: float | Literal["argmax"] | None = None,
    fast: bool = False,
    threads: int | None = None,
    progress: Union[bool, Callable[[int, int], object], None] = None,
) -> Detection:
    """Finds the sharp edges and boundaries of the point cloud ``xyz``.

    ``xyz`` is an (n, 3) float32 or float64 array (any memory layout). float32 coordinates
    are used as they are; float64 ones are re-centred first, so UTM-sized coordinates keep
    their precision. Both as the ``bounded detect`` command treats a file's floats and
    doubles, so the same cloud gets the same result.

    ``model``: a ``Model`` or the path of a model file (default: the embedded model).
    ``scales``: replaces the model's neighbourhood sizes (as many, largest first).
    ``fast``: runs a two-stage model's first stage alone (about half the time).
    ``sensitivity`` in (0, 1): a point is sharp when its sharp probability reaches
    ``1 - sensitivity``; ``"argmax"``: the most probable class wins (default: the model's
    ``sensitivity``, chosen on validation clouds when it was trained).
    ``threads``: limits the worker threads (default: every core).
    ``progress``: ``True`` for a percentage on ``sys.stderr``, or a callable called as
    ``progress(points_done, points)``; its exception is raised when the detection ends.

    The GIL is released while it works. Raises ``ValueError`` for a cloud the model cannot
    label (NaN coordinates, fewer points than the largest scale) or bad options,
    ``TypeError`` for an array of another dtype."""

def features(
    xyz: _Positions,
    scales: Sequence[int] = (128, 64, 32, 16),
    groups: Sequence[_Group] | None = None,
    *,
    threads: int | None = None,
) -> npt.NDArray[np.float32]:
    """BoundED's multi-scale neighbourhood features of every point of ``xyz``.

    Returns float32 of shape (n, len(scales), features per scale): ``result[i, j]`` are
    point ``i``'s features at scale ``j`` (``scales[j]`` neighbours, the point included;
    strictly descending), in the order of ``feature_names(groups)``. The default groups are
    BoundED's 12 features: ``sigma_u`` (3), ``sigma_l`` (3), ``d`` (2), ``s`` (2), ``c`` (2).
    """

def feature_names(groups: Sequence[_Group] | None = None) -> list[str]:
    """The names of the features of one scale, in the order of ``features``' last axis."""

def read(
    path: _Path, *, drop_non_finite: bool = False
) -> tuple[_Positions, dict[str, np.ndarray]]:
    """Reads ``path`` (``.ply`` ``.pcd`` ``.xyz`` ``.txt`` ``.csv`` ``.las`` ``.laz``
    ``.e57``): ``(xyz, fields)``, the positions as (n, 3) float32 (a file of floats) or
    float64, exactly as stored, and every other property as a 1-D array of the file's type.

    ``drop_non_finite=True`` leaves out points with a NaN or infinite coordinate (with a
    warning) instead of raising ``ValueError``."""

def write(path: _Path, xyz: _Positions, /, **fields: npt.ArrayLike) -> None:
    """Writes ``xyz`` and the per-point ``fields`` (1-D arrays of n values: uint8, int8,
    uint16, int16, uint32, int32, float32, float64 or bool) to ``path``, in the format its
    extension names; atomically (a failure leaves no file)."""

_PlannedInput = tuple[str, tuple[float, float, float], tuple[float, float, float], int]

def plan_survey(inputs: Sequence[_Path], *, drop_non_finite: bool = False) -> list[_PlannedInput]:
    """Plans the survey of the files ``inputs``: one tile each, in this order, with the bounds
    of its points (a LAS or LAZ header's, or one read of any other format). Returns
    ``(path, lower corner, upper corner, points)`` per input, plain data that
    ``detect_tile`` takes back in any process."""

def detect_tile(
    plan: Sequence[_PlannedInput],
    tile: int,
    output: _Path,
    *,
    model: _Path | None = None,
    embedded: Literal["row", "band"] | None = None,
    scales: Sequence[int] | None = None,
    sensitivity: float | Literal["argmax"] | None = None,
    fast: bool = False,
    drop_non_finite: bool = False,
    radius: float | None = None,
    block_points: int | None = None,
    threads: int | None = None,
) -> dict[str, float]:
    """Labels tile ``tile`` of ``plan`` with the halo that makes its labels those of the whole
    survey labelled as one cloud, and writes it to ``output`` (atomically: a retried task
    rewrites the same file), by the model file ``model`` or the embedded model ``embedded``
    (``Model.embedded``'s names; default ``"row"``). Returns ``points``, ``halo``, ``labelled``, ``radius``,
    ``attempts``, ``detection_seconds`` and ``seconds``. The GIL is released while it works."""
