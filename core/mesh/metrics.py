"""What a smoothing run changed: how far vertices moved (largest, RMS), the bounding box, and the shrinkage
the paper is about: for closed meshes the enclosed volume, for open ones the mean move along the input's
vertex normals (a closed mesh's volume says what that mean would, without a pass of normals over the input).

Examples
--------
>>> import numpy as np, core
>>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
>>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
>>> round(core.measure_change(positions, positions * 1.1, faces=faces).volume_change, 4)
0.331
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import parallel
from ..geometry import fan_triangles, vertex_normals
from ..parallel import VECTOR_BLOCK
from ..validation import bbox_diagonal, check_positions, row_lengths
from .topology import closed_from_triangles


@dataclass(frozen=True)
class Change:
    """What a smoothing run changed, as ``measure_change`` finds it; ``summary()`` says it in a line.

    Lengths are in the positions' units, relative changes are fractions (0.01: one per cent).

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> change = core.measure_change(positions, positions * 1.1, faces=faces)
    >>> print(*change.summary().split(", "), sep="\\n")
    3 of 4 vertices moved
    largest move 5.77% (0.1)
    RMS 5.00% (0.0866)
    volume +33.10%
    >>> change.closed, round(change.volume_change, 4), round(change.bbox_change, 4)
    (True, 0.331, 0.1)
    """

    n_vertices: int
    moved: int  # vertices whose position differs at all
    mean_displacement: float
    max_displacement: float
    rms_displacement: float
    # mean move along the input's vertex normals (< 0: inwards); None: closed (its volume says it) or no faces
    normal_displacement: float | None
    bbox_diagonal_before: float
    bbox_diagonal_after: float
    bbox_change: float  # relative change of the bounding-box diagonal
    closed: bool  # faces given and every edge shared by exactly two faces, in opposite directions
    volume_before: float | None
    volume_after: float | None
    volume_change: float | None  # relative; None when not closed (or no faces)

    def summary(self):
        """The report's words, the same in the operators, the command line and the demo: how many vertices
        moved, the largest and the RMS move (in % of the size, the input's bounding-box diagonal, and in the
        positions' units), and the volume change of a closed mesh or the mean move along an open one's normals."""
        parts = [f"{self.moved} of {_count(self.n_vertices, 'vertex', 'vertices')} moved"]
        if self.moved:
            parts.append(f"largest move {self._of_size(self.max_displacement)}")
            parts.append(f"RMS {self._of_size(self.rms_displacement)}")
            if self.normal_displacement is not None:
                parts.append(f"along the normals {self._of_size(self.normal_displacement, '+')}")
        if self.volume_change is not None:
            parts.append(f"volume {self.volume_change:+.2%}")
        return ", ".join(parts)

    def brief(self):
        """The summary's two headline figures, for a table: the largest move and the volume change."""
        text = f"largest move {self._of_size(self.max_displacement)}"
        return text + (f", volume {self.volume_change:+.2%}" if self.volume_change is not None else "")

    def _of_size(self, length, sign=""):
        """'0.31 % (0.0124)': a length in % of the size and in the positions' units."""
        share = length / self.bbox_diagonal_before if self.bbox_diagonal_before else 0.0
        return f"{share:{sign}.2%} ({length:{sign}.3g})"


def _count(number, one, many):
    return f"{number} {one if number == 1 else many}"


def _rms(lengths):
    if not lengths.size:
        return 0.0
    scale = float(lengths.max())  # no overflow or underflow in the squares
    if scale == 0.0:
        return 0.0
    scaled = lengths / lengths.dtype.type(scale)
    return scale * math.sqrt(float(np.einsum("i,i->", scaled, scaled, dtype=np.float64)) / lengths.size)


def enclosed_volume(positions, triangles):
    """Signed volume by the divergence theorem (positive for outward-facing normals).

    Parameters
    ----------
    positions : (n, 3) float ndarray
    triangles : (t, 3) int ndarray
        A closed surface (see ``fan_triangles`` for other faces).

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh import metrics
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> round(float(metrics.enclosed_volume(positions, triangles)), 4)
    0.1667
    """
    return enclosed_volumes(triangles, positions)[0]


def enclosed_volumes(triangles, *position_sets):
    """The signed volume of each set of (n, 3) positions on the same triangles: one pass over the
    triangles each, in the positions' own precision.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh import metrics
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> [round(float(v), 4) for v in metrics.enclosed_volumes(triangles, positions, 2 * positions)]
    [0.1667, 1.3333]
    """
    corners = _corner_columns(triangles)
    frame = _Frame.of(position_sets[0] if position_sets else np.zeros((0, 3)))
    return [frame.volume(points, corners) for points in position_sets]


def _corner_columns(triangles):
    return tuple(np.ascontiguousarray(triangles[:, k]) for k in range(3))


@dataclass(frozen=True)
class _Frame:
    """Where volumes are measured from: a point near the surface (the volume does not change under
    translation, and measured from there its terms do not cancel, so single precision keeps its
    digits far from the origin) in a power-of-two unit near the size (no overflow or underflow)."""

    centre: np.ndarray
    unit: float

    @classmethod
    def of(cls, points):
        if not len(points):
            return cls(np.zeros(3), 1.0)
        centre = np.array([float(points[:, k].min()) / 2 + float(points[:, k].max()) / 2 for k in range(3)])
        size = bbox_diagonal(points)
        return cls(centre, 2.0 ** math.frexp(size)[1] if size > 0.0 and math.isfinite(size) else 1.0)

    def volume(self, points, corners):
        return self.units(points, corners) * self.unit * self.unit * self.unit

    def units(self, points, corners):
        """Σ a·(b×c) / 6 over the triangles (a, b, c) (``corners``: their three index columns), in unit³."""
        tasks, total = _volume_tasks(points, corners, self, parts=1)
        return total([task() for task in tasks])


def _volume_tasks(points, corners, frame, parts):
    """The volume of ``frame.units`` as ``parts`` tasks over runs of blocks, and the function that adds
    their results up in block order (the same bits however the tasks ran)."""
    local, unit = _in_frame(points, frame)
    rows = _whole_rows(local)
    count = corners[0].size
    blocks = [(start, min(start + _VOLUME_BLOCK, count)) for start in range(0, count, _VOLUME_BLOCK)]
    share = max(1, -(-len(blocks) // parts))
    tasks = [
        lambda run=blocks[i : i + share]: _block_sums(rows, local.dtype, corners, run)
        for i in range(0, max(1, len(blocks)), share)
    ]

    def total(results):
        value = 0.0
        for block_sum in (block_sum for sums in results for block_sum in sums):
            value += block_sum
        return value / 6.0 / (unit * unit * unit)

    return tasks, total


_VOLUME_BLOCK = VECTOR_BLOCK  # triangles per block: few NumPy calls, each on data that stays in cache


def _whole_rows(points):
    """(n, 3) points as n items of four coordinates (the fourth 0), so that gathering rows is one take of
    16- or 32-byte items, several times faster than a take of 3-coordinate rows."""
    padded = np.empty((len(points), 4), dtype=points.dtype)
    padded[:, :3] = points
    padded[:, 3] = 0.0
    return padded.view(np.dtype((np.void, padded.strides[0]))).ravel()


def _block_sums(rows, dtype, corners, blocks):
    """Σ a·(b×c) over the triangles of each block; each corner gathers whole rows (``_whole_rows``: one take
    per corner, not one per coordinate)."""
    sums = []
    for start, stop in blocks:
        a, b, c = (np.take(rows, index[start:stop]).view(dtype).reshape(-1, 4) for index in corners)
        bx, by, bz, cx, cy, cz = b[:, 0], b[:, 1], b[:, 2], c[:, 0], c[:, 1], c[:, 2]
        term = by * cz
        term -= bz * cy
        term *= a[:, 0]
        part = bz * cx
        part -= bx * cz
        part *= a[:, 1]
        term += part
        part = bx * cy
        part -= by * cx
        part *= a[:, 2]
        term += part
        sums.append(float(term.sum(dtype=np.float64)))
    return sums


def _in_frame(points, frame):
    """(points measured in ``frame``, the unit they are in, relative to frame.unit). A copy only where it
    matters: far from the origin (terms would cancel) or at sizes whose cubes leave the dtype's range."""
    size = frame.unit
    near = float(np.abs(frame.centre).max(initial=0.0)) <= size
    if near and _cubes_are_safe(size, points.dtype):
        return points, size
    local = points - frame.centre.astype(points.dtype)
    local /= points.dtype.type(frame.unit)
    return local, 1.0


def _cubes_are_safe(length, dtype):
    """Whether products of three coordinates up to ``length`` (and a millionth of it) stay normal numbers."""
    info = np.finfo(dtype)
    return np.cbrt(info.tiny) * 1e6 < length < np.cbrt(info.max) / 4


@dataclass(frozen=True)
class InputMeasure:
    """What a report needs of a run's input, measured once (``measure_input``): ``measure_change`` takes
    it so that a caller can measure the input while the run starts (on another thread) and only the
    result afterwards.

    Examples
    --------
    >>> import numpy as np, core
    >>> tetrahedron = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> measured = core.measure_input(tetrahedron, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> measured.n_vertices, measured.closed
    (4, True)
    """

    n_vertices: int
    diagonal: float
    closed: bool
    frame: _Frame
    corners: tuple | None  # the triangles' corner columns of a closed surface, for the result's volume
    volume_units: float | None  # the input's volume in frame.unit³
    normals: np.ndarray | None = None  # the input's unit vertex normals (faces, not closed), for the move along them


def measure_input(before: ArrayLike, faces=None, closed: bool | None = None) -> InputMeasure:
    """The input's side of ``measure_change`` (same arguments, without ``after``).

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.mesh import metrics
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> measured = metrics.measure_input(positions, faces)
    >>> measured.closed, measured.n_vertices
    (True, 4)
    >>> print(*core.measure_change(positions, positions * 1.1, measured=measured).summary().split(", "), sep="\\n")
    3 of 4 vertices moved
    largest move 5.77% (0.1)
    RMS 5.00% (0.0866)
    volume +33.10%
    """
    before = check_positions(before, "before")
    closed = closed if faces is not None else False
    corners = normals = None
    if faces is not None:
        triangles = fan_triangles(faces)
        if triangles.size and (triangles.max() >= before.shape[0] or triangles.min() < 0):
            raise ValueError("faces refer to vertices that do not exist")
        if closed is not False:  # an open surface has no volume to compare
            closed = closed_from_triangles(triangles) if closed is None else bool(closed)
            corners = _corner_columns(triangles) if closed else None
        if not closed:  # a closed surface's volume says what the move along its normals would
            normals = vertex_normals(_in_frame(before, _Frame.of(before))[0], triangles, before.dtype)
    frame = _Frame.of(before)
    return InputMeasure(
        n_vertices=before.shape[0],
        diagonal=bbox_diagonal(before),
        closed=closed,
        frame=frame,
        corners=corners,
        volume_units=frame.units(before, corners) if corners is not None else None,
        normals=normals,
    )


def measure_change(
    before: ArrayLike, after: ArrayLike, faces=None, closed: bool | None = None, measured: InputMeasure | None = None
) -> Change:
    """Compare a smoothing result with its input: displacements, bounding box and, closed, volume.

    Parameters
    ----------
    before, after : (n, 3) array_like of float32 or float64
        The input and the result, vertex for vertex.
    faces : optional
        As for ``fan_triangles``; needed for the volume.
    closed : bool, optional
        Whether the faces form a closed, consistently oriented surface, when the caller already knows
        (Blender's edge data tells it cheaply); None checks it here.
    measured : InputMeasure, optional
        ``measure_input`` of the same before, faces and closed, if the caller has it (then those are
        not looked at again).

    Returns
    -------
    Change

    Raises
    ------
    ValueError
        Shapes that differ or are not (n, 3), NaN or infinite coordinates, faces that refer to
        vertices that do not exist.

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> print(*core.measure_change(positions, positions * 1.1, faces=faces).summary().split(", "), sep="\\n")
    3 of 4 vertices moved
    largest move 5.77% (0.1)
    RMS 5.00% (0.0866)
    volume +33.10%
    >>> core.measure_change(positions, positions * 1.1).summary()  # no faces: no volume
    '3 of 4 vertices moved, largest move 5.77% (0.1), RMS 5.00% (0.0866)'
    """
    before, after = check_positions(before, "before"), check_positions(after, "after")
    if before.shape != after.shape:
        raise ValueError(f"before and after must have the same shape, got {before.shape} and {after.shape}")
    measured = measure_input(before, faces, closed) if measured is None else measured
    if measured.n_vertices != before.shape[0]:
        raise ValueError(f"measured is of {measured.n_vertices} vertices, before has {before.shape[0]}")

    def displacements():  # in the arrays' own precision (a report, not a result): no float64 copies
        diagonal = bbox_diagonal(after)
        moves = after - before
        along = None
        if measured.normals is not None and moves.size:
            along = float(np.einsum("ij,ij->i", moves, measured.normals).mean(dtype=np.float64))
        return diagonal, row_lengths(moves, max(measured.diagonal, diagonal)), along

    # A big closed mesh: its volume in parts on every thread, beside the displacements.
    volume_tasks, volume_total = [], None
    if measured.corners is not None:
        big = measured.corners[0].size >= 2 * _VOLUME_BLOCK
        parts = parallel.thread_count() if big else 1
        volume_tasks, volume_total = _volume_tasks(after, measured.corners, measured.frame, parts)
    tasks = [displacements, *volume_tasks]
    results = parallel.run_all(tasks) if len(tasks) > 2 else [task() for task in tasks]
    diag_after, displacement, along = results[0]
    after_units = volume_total(results[1:]) if volume_total else None
    diag_before, unit = measured.diagonal, measured.frame.unit
    volume_before = volume_after = volume_change = None
    if after_units is not None:
        volume_before, volume_after = (units * unit * unit * unit for units in (measured.volume_units, after_units))
        if measured.volume_units != 0.0:
            volume_change = (after_units - measured.volume_units) / abs(measured.volume_units)
    return Change(
        n_vertices=before.shape[0],
        moved=int(np.count_nonzero(displacement)),
        mean_displacement=float(displacement.mean(dtype=np.float64)) if displacement.size else 0.0,
        max_displacement=float(displacement.max()) if displacement.size else 0.0,
        rms_displacement=_rms(displacement),
        normal_displacement=along,
        bbox_diagonal_before=diag_before,
        bbox_diagonal_after=diag_after,
        bbox_change=(diag_after - diag_before) / diag_before if diag_before else 0.0,
        closed=measured.closed,
        volume_before=volume_before,
        volume_after=volume_after,
        volume_change=volume_change,
    )
