"""Normals of a smoothed surface, for the files that carry normals.

A stored normal is the sum, over the face corners that use it, of the corner's face normal weighted by
the corner's angle, normalised: for a vertex normal (PLY nx/ny/nz, an OBJ `vn` used by every corner of
a vertex) that is Blender's vertex normal; for an OBJ `vn` used by one face (flat shading) it is that
face's normal; for a `vn` shared by the faces of one smooth group it is the group's normal at that
vertex. A polygon's normal is its vector area's direction (Newell's normal), as Blender's is.
"""

import numpy as np

from ... import core


def corner_neighbours(starts, sizes):
    """For each corner of the faces (corners stored face after face), the next and the previous corner."""
    count = int(sizes.sum())
    corner = np.arange(count)
    first = np.repeat(starts, sizes)
    last = first + np.repeat(sizes, sizes) - 1
    following = np.where(corner == last, first, corner + 1)
    preceding = np.where(corner == first, last, corner - 1)
    return following, preceding


def face_normals(positions, corners, starts, sizes):
    """Unit normal of each face; (0, 0, 0) for a face without area. A polygon's is the sum of its fan's
    triangle vectors (its vector area, which Newell's method gives), normalised."""
    if not len(starts):
        return np.zeros((0, 3))
    offsets = np.append(starts, len(corners))
    vectors = core.face_vectors(positions, core.fan_triangles((offsets, corners)))
    fans = sizes - 2  # triangles per face
    return core.unit_rows(np.add.reduceat(vectors, np.cumsum(fans) - fans, axis=0))


def corner_vectors(positions, corners, starts, sizes):
    """Each corner's face normal times the corner's angle (float64)."""
    positions = np.asarray(positions, dtype=np.float64)
    following, preceding = corner_neighbours(starts, sizes)
    faces = face_normals(positions, corners, starts, sizes)
    here = positions[corners]
    a = core.unit_rows(positions[corners[following]] - here)
    b = core.unit_rows(positions[corners[preceding]] - here)
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0))
    return np.repeat(faces, sizes, axis=0) * angle[:, None]


def stored_normals(positions, corners, starts, sizes, targets, count):
    """The normals of ``count`` stored normals, corner i adding to normal targets[i] (-1: none).

    Returns (normals, used): ``used`` marks the stored normals some corner adds to and that came out
    non-zero; the others keep their stored values."""
    vectors = corner_vectors(positions, corners, starts, sizes)
    take = targets >= 0
    sums = np.zeros((count, 3))
    _add(sums, targets[take], vectors[take])
    used = np.linalg.norm(sums, axis=1) > 0
    return core.unit_rows(sums), used


def _add(sums, index, vectors):
    for axis in range(3):  # bincount: far faster than np.add.at
        sums[:, axis] += np.bincount(index, weights=vectors[:, axis], minlength=len(sums))


def touched(moved, corners, starts, sizes, targets, count):
    """Which stored normals a moved vertex can change: those used by a corner of a face that has one."""
    face_moved = np.add.reduceat(moved[corners].astype(np.int64), starts) > 0 if len(starts) else np.zeros(0, bool)
    corner_moved = np.repeat(face_moved, sizes)
    take = (targets >= 0) & corner_moved
    result = np.zeros(count, dtype=bool)
    result[targets[take]] = True
    return result
