"""What a smoothing run changed: displacement, bounding box and, for closed meshes, enclosed volume."""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .validation import bbox_diagonal, check_positions


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
        parts = [f"{self.moved} of {self.n_vertices} vertices moved (mean {self.mean_displacement:.3g}, "
                 f"max {self.max_displacement:.3g})"]
        if self.volume_change is not None:
            parts.append(f"volume {self.volume_change:+.2%}")
        else:
            parts.append(f"bounding box {self.bbox_change:+.2%}")
        return ", ".join(parts)


def fan_triangles(faces):
    """Triangles (t, 3) of a fan from each face's first corner.

    ``faces``: an (f, k) integer array, or a pair (offsets, corner_verts) as Blender stores polygons
    (offsets of length f + 1: face i has corners corner_verts[offsets[i]:offsets[i + 1]]).
    """
    if isinstance(faces, tuple):
        offsets, corners = (np.asarray(a, dtype=np.int64) for a in faces)
        if offsets.ndim != 1 or offsets.size == 0 or offsets[0] != 0 or offsets[-1] != corners.size \
                or np.any(np.diff(offsets) < 3):
            raise ValueError("faces as (offsets, corner_verts) need offsets from 0 to len(corner_verts), "
                             "at least 3 corners per face")
    else:
        array = np.asarray(faces, dtype=np.int64)
        if array.ndim != 2 or array.shape[1] < 3:
            raise ValueError(f"faces must have shape (f, k) with k >= 3, got {array.shape}")
        corners = array.ravel()
        offsets = np.arange(array.shape[0] + 1, dtype=np.int64) * array.shape[1]
    sizes = np.diff(offsets)
    if sizes.size and corners.size == sizes[0] * sizes.size and np.all(sizes == sizes[0]):
        # All faces alike (all triangles, all quads...): the fans are column picks of an (f, k) view.
        k = int(sizes[0])
        grid = corners.reshape(-1, k)
        return np.stack([grid[:, [0, j + 1, j + 2]] for j in range(k - 2)], axis=1).reshape(-1, 3)
    face_of_triangle = np.repeat(np.arange(sizes.size), sizes - 2)
    # Triangle k of face f: corners (0, k+1, k+2) counted from the face's first corner.
    k = np.arange(face_of_triangle.size) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
    first = offsets[face_of_triangle]
    return np.stack([corners[first], corners[first + k + 1], corners[first + k + 2]], axis=1)


def is_closed(triangles_or_faces):
    """Every directed boundary edge of the faces is matched by exactly one edge in the opposite direction."""
    triangles = triangles_or_faces
    if triangles.size == 0:
        return False
    heads = triangles.ravel()
    tails = np.roll(triangles, -1, axis=1).ravel()
    n = int(triangles.max()) + 1
    # Fan diagonals appear once in each direction inside their own face, so they cancel like real edges.
    # Directed-edge counts as a sparse matrix D (SciPy's O(nnz) placement, no global sort): closed and
    # consistently oriented <=> every directed edge once (entries all 1) and D == D^T.
    counts = sp.coo_matrix((np.ones(heads.size, dtype=np.int32), (heads, tails)), shape=(n, n)).tocsr()
    if counts.nnz != heads.size:  # a directed edge used twice: duplicate faces or flipped neighbours
        return False
    return (counts != counts.T.tocsr()).nnz == 0


def enclosed_volume(positions, triangles):
    """Signed volume by the divergence theorem (positive for outward-facing normals)."""
    return _signed_volume(_columns(positions), _columns(triangles))


def _columns(array):
    """The columns of an (n, 3) array as contiguous 1-D arrays (float64 for points): gathers and
    element-wise products on them run several times faster than on the narrow rows."""
    array = np.asarray(array)
    dtype = np.float64 if array.dtype.kind == "f" else None
    return [np.ascontiguousarray(array[:, k], dtype=dtype) for k in range(3)]


def _signed_volume(xyz, corners):
    """Σ a·(b×c) / 6 over the triangles (a, b, c), written out per coordinate."""
    x, y, z = xyz
    a, b, c = corners
    ax, ay, az = x[a], y[a], z[a]
    bx, by, bz = x[b], y[b], z[b]
    cx, cy, cz = x[c], y[c], z[c]
    total = np.dot(ax, by * cz - bz * cy) + np.dot(ay, bz * cx - bx * cz) + np.dot(az, bx * cy - by * cx)
    return float(total / 6.0)


def measure_change(before, after, faces=None, closed=None):
    """Compare a smoothing result with its input (both (n, 3)); ``faces`` as for ``fan_triangles``.

    ``closed``: whether the faces form a closed, consistently oriented surface, when the caller already
    knows (Blender's edge data tells it cheaply); None checks it here.
    """
    before, after = check_positions(before, "before"), check_positions(after, "after")
    if before.shape != after.shape:
        raise ValueError(f"before and after must have the same shape, got {before.shape} and {after.shape}")
    # In the arrays' own precision (a report, not a result): no float64 copies of a million rows.
    step = after - before
    displacement = np.sqrt(np.einsum("ij,ij->i", step, step))
    del step
    diag_before, diag_after = bbox_diagonal(before), bbox_diagonal(after)
    closed = closed if faces is not None else False
    volume_before = volume_after = volume_change = None
    if faces is not None and closed is not False:  # an open surface has no volume to compare
        triangles = fan_triangles(faces)
        if triangles.size and triangles.max() >= before.shape[0]:
            raise ValueError("faces refer to vertices that do not exist")
        closed = is_closed(triangles) if closed is None else bool(closed)
        if closed:
            corners = _columns(triangles)
            volume_before = _signed_volume(_columns(before), corners)
            volume_after = _signed_volume(_columns(after), corners)
            if volume_before != 0.0:
                volume_change = (volume_after - volume_before) / abs(volume_before)
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
