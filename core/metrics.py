"""What a smoothing run changed: displacement, bounding box and, for closed meshes, enclosed volume."""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import parallel
from .topology import closed_from_triangles
from .validation import bbox_diagonal, check_positions, row_lengths


@dataclass(frozen=True)
class Change:
    n_vertices: int
    moved: int  # vertices whose position differs at all
    mean_displacement: float
    max_displacement: float
    bbox_diagonal_before: float
    bbox_diagonal_after: float
    bbox_change: float  # relative change of the bounding-box diagonal
    closed: bool  # faces given and every edge shared by exactly two faces, in opposite directions
    volume_before: float | None
    volume_after: float | None
    volume_change: float | None  # relative; None when not closed (or no faces)

    def summary(self):
        parts = [
            f"{self.moved} of {self.n_vertices} vertices moved (mean {self.mean_displacement:.3g}, "
            f"max {self.max_displacement:.3g})"
        ]
        if self.volume_change is not None:
            parts.append(f"volume {self.volume_change:+.2%}")
        else:
            parts.append(f"bounding box {self.bbox_change:+.2%}")
        return ", ".join(parts)


def fan_triangles(faces):
    """Triangles (t, 3) of a fan from each face's first corner (triangles come back as they are, no copy).

    ``faces``: an (f, k) integer array, or a pair (offsets, corner_verts) as Blender stores polygons
    (offsets of length f + 1: face i has corners corner_verts[offsets[i]:offsets[i + 1]]).
    """
    if isinstance(faces, tuple):
        offsets, corners = (_indices(a) for a in faces)
        if (
            offsets.ndim != 1
            or offsets.size == 0
            or offsets[0] != 0
            or offsets[-1] != corners.size
            or np.any(np.diff(offsets) < 3)
        ):
            raise ValueError(
                "faces as (offsets, corner_verts) need offsets from 0 to len(corner_verts), at least 3 corners per face"
            )
        if corners.size == 3 * (offsets.size - 1):  # no face has fewer than three corners: all are triangles
            return corners.reshape(-1, 3)
    else:
        array = _indices(faces)
        if array.ndim != 2 or array.shape[1] < 3:
            raise ValueError(f"faces must have shape (f, k) with k >= 3, got {array.shape}")
        if array.shape[1] == 3:
            return array
        corners = array.ravel()
        offsets = np.arange(array.shape[0] + 1, dtype=np.int64) * array.shape[1]
    sizes = np.diff(offsets)
    if sizes.size and corners.size == sizes[0] * sizes.size and np.all(sizes == sizes[0]):
        # All faces alike (all quads...): the fans are column picks of an (f, k) view.
        k = int(sizes[0])
        grid = corners.reshape(-1, k)
        return np.stack([grid[:, [0, j + 1, j + 2]] for j in range(k - 2)], axis=1).reshape(-1, 3)
    face_of_triangle = np.repeat(np.arange(sizes.size), sizes - 2)
    # Triangle k of face f: corners (0, k+1, k+2) counted from the face's first corner.
    k = np.arange(face_of_triangle.size) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
    first = offsets[face_of_triangle]
    return np.stack([corners[first], corners[first + k + 1], corners[first + k + 2]], axis=1)


def _indices(array):
    """An integer array as given (int32 stays int32), anything else as int64."""
    array = np.asarray(array)
    return array if np.issubdtype(array.dtype, np.integer) else array.astype(np.int64)


def enclosed_volume(positions, triangles):
    """Signed volume by the divergence theorem (positive for outward-facing normals)."""
    return enclosed_volumes(triangles, positions)[0]


def enclosed_volumes(triangles, *position_sets):
    """The signed volume of each set of (n, 3) positions on the same triangles: one pass over the
    triangles each, in the positions' own precision, the sets side by side on threads."""
    volumes, unit = _volumes_in_units(triangles, position_sets)
    return [volume * unit * unit * unit for volume in volumes]


def _volumes_in_units(triangles, position_sets):
    """(volumes, unit): the volumes measured in a power of two near the size of the first set, so
    that their terms neither overflow nor underflow (and their ratios hold at any scale)."""
    corners = [np.ascontiguousarray(triangles[:, k]) for k in range(3)]
    # The volume does not change under translation; measured from a point near the surface the terms
    # do not cancel, so single precision keeps its digits even far from the origin.
    first = position_sets[0] if position_sets else np.zeros((0, 3))
    centre = _box_centre(first) if len(first) else np.zeros(3)
    size = bbox_diagonal(first)
    unit = 2.0 ** math.frexp(size)[1] if size > 0.0 and math.isfinite(size) else 1.0
    tasks = [lambda points=points: _signed_volume(points, corners, centre, unit) for points in position_sets]
    if len(tasks) > 1 and corners[0].size >= _VOLUME_BLOCK * 8 and parallel.thread_count() > 1:
        return parallel.run_all(tasks), unit
    return [task() for task in tasks], unit


_VOLUME_BLOCK = 1 << 14  # triangles per block: the gathered corners of a block stay in cache


def _box_centre(points):
    return np.array([float(points[:, k].min()) / 2 + float(points[:, k].max()) / 2 for k in range(3)])


def _signed_volume(points, corners, centre, unit):
    """Σ a·(b×c) / 6 over the triangles (a, b, c) of the points in ``unit``s from ``centre``, written
    out per coordinate, block by block."""
    x, y, z = ((points[:, k] - points.dtype.type(centre[k])) / points.dtype.type(unit) for k in range(3))
    a_all, b_all, c_all = corners
    total = 0.0
    for start in range(0, a_all.size, _VOLUME_BLOCK):
        a, b, c = (index[start : start + _VOLUME_BLOCK] for index in (a_all, b_all, c_all))
        bx, by, bz, cx, cy, cz = x[b], y[b], z[b], x[c], y[c], z[c]
        term = by * cz
        term -= bz * cy
        term *= x[a]
        part = bz * cx
        part -= bx * cz
        part *= y[a]
        term += part
        bx *= cy
        by *= cx
        bx -= by
        bx *= z[a]
        term += bx
        total += float(term.sum(dtype=np.float64))
    return total / 6.0


def measure_change(before: ArrayLike, after: ArrayLike, faces=None, closed: bool | None = None) -> Change:
    """Compare a smoothing result with its input (both (n, 3)); ``faces`` as for ``fan_triangles``.

    ``closed``: whether the faces form a closed, consistently oriented surface, when the caller already
    knows (Blender's edge data tells it cheaply); None checks it here.
    """
    before, after = check_positions(before, "before"), check_positions(after, "after")
    if before.shape != after.shape:
        raise ValueError(f"before and after must have the same shape, got {before.shape} and {after.shape}")
    # In the arrays' own precision (a report, not a result): no float64 copies of a million rows.
    diag_before, diag_after = bbox_diagonal(before), bbox_diagonal(after)
    displacement = row_lengths(after - before, max(diag_before, diag_after))
    closed = closed if faces is not None else False
    volume_before = volume_after = volume_change = None
    if faces is not None and closed is not False:  # an open surface has no volume to compare
        triangles = fan_triangles(faces)
        if triangles.size and triangles.max() >= before.shape[0]:
            raise ValueError("faces refer to vertices that do not exist")
        closed = closed_from_triangles(triangles) if closed is None else bool(closed)
        if closed:
            (before_units, after_units), unit = _volumes_in_units(triangles, (before, after))
            volume_before, volume_after = (units * unit * unit * unit for units in (before_units, after_units))
            if before_units != 0.0:
                volume_change = (after_units - before_units) / abs(before_units)
    return Change(
        n_vertices=before.shape[0],
        moved=int(np.count_nonzero(displacement)),
        mean_displacement=float(displacement.mean(dtype=np.float64)) if displacement.size else 0.0,
        max_displacement=float(displacement.max()) if displacement.size else 0.0,
        bbox_diagonal_before=diag_before,
        bbox_diagonal_after=diag_after,
        bbox_change=(diag_after - diag_before) / diag_before if diag_before else 0.0,
        closed=closed,
        volume_before=volume_before,
        volume_after=volume_after,
        volume_change=volume_change,
    )
