"""What a smoothing run changed: displacement, bounding box and, for closed meshes, enclosed volume."""

from dataclasses import dataclass

import numpy as np

from .validation import check_positions


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
    forward = np.sort(heads * n + tails)
    backward = np.sort(tails * n + heads)
    unique_forward = forward.size == np.unique(forward).size
    return bool(unique_forward and np.array_equal(forward, backward))


def enclosed_volume(positions, triangles):
    """Signed volume by the divergence theorem (positive for outward-facing normals)."""
    p = np.asarray(positions, dtype=np.float64)
    a, b, c = p[triangles[:, 0]], p[triangles[:, 1]], p[triangles[:, 2]]
    return float(np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0)


def _bbox_diagonal(points):
    if points.shape[0] == 0:
        return 0.0
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def measure_change(before, after, faces=None):
    """Compare a smoothing result with its input (both (n, 3)); ``faces`` as for ``fan_triangles``."""
    before = check_positions(before, "before").astype(np.float64, copy=False)
    after = check_positions(after, "after").astype(np.float64, copy=False)
    if before.shape != after.shape:
        raise ValueError(f"before and after must have the same shape, got {before.shape} and {after.shape}")
    displacement = np.linalg.norm(after - before, axis=1)
    diag_before, diag_after = _bbox_diagonal(before), _bbox_diagonal(after)
    closed = False
    volume_before = volume_after = volume_change = None
    if faces is not None:
        triangles = fan_triangles(faces)
        if triangles.size and triangles.max() >= before.shape[0]:
            raise ValueError("faces refer to vertices that do not exist")
        closed = is_closed(triangles)
        if closed:
            volume_before = enclosed_volume(before, triangles)
            volume_after = enclosed_volume(after, triangles)
            if volume_before != 0.0:
                volume_change = (volume_after - volume_before) / abs(volume_before)
    return Change(
        n_vertices=before.shape[0],
        moved=int(np.count_nonzero(displacement)),
        mean_displacement=float(displacement.mean()) if displacement.size else 0.0,
        max_displacement=float(displacement.max()) if displacement.size else 0.0,
        bbox_diagonal_before=diag_before,
        bbox_diagonal_after=diag_after,
        bbox_change=(diag_after - diag_before) / diag_before if diag_before else 0.0,
        closed=closed,
        volume_before=volume_before,
        volume_after=volume_after,
        volume_change=volume_change,
    )
