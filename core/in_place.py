"""Keep in Place: each vertex moves across the surface, never along it.

A smoother's move of a vertex has two parts: one along the surface's normal, which removes the noise
that scanners put there, and one along the surface (the *slide*), which removes no noise but moves what
the vertex carries (a texture's point, a UV, an outline's place): a uniform umbrella pulls vertices
towards the centre of their neighbours, so irregular scans drift and open borders pull in.

``keep_in_place`` keeps only the first part: the input position plus the move's component along the
result's unit vertex normal. The vertex then lies on the smoothed surface's tangent plane at the place
the smoother took it to, over its input. It runs once, after the iterations: projecting every
iteration's move instead leaves the mesh as irregular as the noise made it, and the umbrella's normal
component on an irregular mesh brings bumps back (bench/README.md, "Keep in Place").
"""

import numpy as np

from .volume import vertex_normals


def keep_in_place(start: np.ndarray, result: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``result`` with each vertex's move from ``start`` reduced to its part along ``result``'s vertex
    normal (area-weighted, core.volume.vertex_normals). Vertices in no triangle (no normal) keep their
    result, and so do the corners of a triangle that keeping would fold or flatten (moves large against
    the edges, on coarse parts); a vertex that did not move stays bit for bit. Returns a new array in
    ``result``'s dtype.

    Examples
    --------
    >>> import numpy as np
    >>> from core.in_place import keep_in_place
    >>> start = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.1]])
    >>> result = start + [[0, 0, 0], [0, 0, 0], [0, 0, 0], [-0.2, -0.2, -0.1]]  # slid and lowered
    >>> keep_in_place(start, result, np.array([[0, 1, 3], [0, 3, 2]])).round(3).tolist()[3]
    [1.0, 1.0, 0.0]
    """
    normals = vertex_normals(result, triangles)
    move = result.astype(np.float64) - start
    along = np.einsum("ij,ij->i", move, normals)
    kept = start + along[:, None] * normals
    bare = ~normals.any(axis=1)  # in no triangle: no surface to keep to
    kept[bare] = result[bare]
    _unfold(kept, start, result, triangles)
    out = kept.astype(result.dtype)
    still = ~move.any(axis=1)
    out[still] = result[still]
    return out


FOLDED = 0.25  # a kept triangle whose area, seen along the smoothed one's normal, is under this share of its input's
_ROUNDS = 4  # vertices given back their smoothed position make new triangles of mixed corners: check again


def _unfold(kept, start, result, triangles):
    """Where keeping the moves across the surface folds or flattens a triangle (a coarse part moved far
    along normals that turn under it: FOLDED), its corners take the smoother's own result, in place."""
    triangles = np.asarray(triangles)
    smoothed = _cross(result, triangles)
    reference = FOLDED * np.linalg.norm(_cross(start, triangles), axis=1)
    length = np.linalg.norm(smoothed, axis=1)
    facing = smoothed / np.where(length > 0, length, 1.0)[:, None]
    for _ in range(_ROUNDS):
        area = np.einsum("ij,ij->i", _cross(kept, triangles), facing)
        bad = np.flatnonzero(area < reference)
        if bad.size == 0:
            return
        corners = np.unique(triangles[bad])
        kept[corners] = result[corners]


def _cross(points, triangles):
    """(t, 3) twice-area normals of ``triangles`` over ``points``."""
    a = points[triangles[:, 0]]
    return np.cross(points[triangles[:, 1]] - a, points[triangles[:, 2]] - a)
