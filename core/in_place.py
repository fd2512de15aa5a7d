"""Keep in Place: each vertex moves across the surface, never along it.

A smoother's move of a vertex has two parts: one along the surface's normal, which removes the noise
that scanners put there, and one along the surface (the *slide*), which removes no noise but moves what
the vertex carries (a texture's point, a UV, an outline's place): a uniform umbrella pulls vertices
towards the centre of their neighbours, so irregular scans drift and open borders pull in.

``keep_in_place`` keeps only the first part: the input position plus the move's component along the
result's unit vertex normal. The vertex then lies on the smoothed surface's tangent plane at the place
the smoother took it to, over its input. It runs once, after the iterations: projecting every
iteration's move instead leaves the mesh as irregular as the noise made it, and the umbrella's normal
component on an irregular mesh brings bumps back (bench/bench_keep_in_place.py, docs/keep_in_place.md).

Where the input's own layout on the surface is folded (noise along the surface larger than the edges),
or large moves along turning normals would fold it, a triangle kept in place would overlap its
neighbours; its corners take back part of the smoother's slide, as much as unfolds it.
"""

import numpy as np
import scipy.sparse as sp

from .volume import vertex_normals

FOLDED = 0.25  # a kept triangle whose shadow on the smoothed surface is under this share of its input's ...
FLAT = 0.1  # ... or whose shadow is under this share of its input's area is flattened
_ROUNDS = 3  # each round halves the kept part of the slide at the corners of the triangles still folded


def keep_in_place(start: np.ndarray, result: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``result`` with each vertex's move from ``start`` reduced to its part along ``result``'s vertex
    normal (area-weighted, core.volume.vertex_normals). Vertices in no triangle (no normal) keep their
    result, and the corners of a triangle that keeping would fold or flatten take back part of the slide
    (see ``unfold``); a vertex that did not move stays bit for bit. Returns a new array in ``result``'s
    dtype.

    Examples
    --------
    >>> import numpy as np
    >>> from core.in_place import keep_in_place
    >>> start = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.1]])
    >>> result = start + [[0, 0, 0], [0, 0, 0], [0, 0, 0], [-0.2, -0.2, -0.1]]  # slid and lowered
    >>> keep_in_place(start, result, np.array([[0, 1, 3], [0, 3, 2]])).round(3).tolist()[3]
    [1.0, 1.0, 0.0]
    """
    triangles = np.asarray(triangles)
    normals = vertex_normals(result, triangles)
    move = result.astype(np.float64) - start
    along = np.einsum("ij,ij->i", move, normals)
    kept = start + along[:, None] * normals
    bare = ~normals.any(axis=1)  # in no triangle: no surface to keep to
    kept[bare] = result[bare]
    unfold(kept, start, result, triangles)
    out = kept.astype(result.dtype)
    still = ~move.any(axis=1)
    out[still] = result[still]
    return out


def unfold(kept, start, result, triangles):
    """Where ``kept`` folds or flattens a triangle, its corners take back part of the slide to ``result``,
    in place: half of what is left of it for each round the triangle stays folded, all of it after
    _ROUNDS rounds (until no triangle with a corner off the result is folded). Shadows are read along the
    smoothed triangle's normal: a kept triangle is folded where its shadow is not positive, flattened
    where it is under FOLDED times the input's shadow or FLAT times the input's area. Later rounds read
    only the triangles at the corners just moved."""
    corners_of = [np.ascontiguousarray(triangles[:, k]) for k in range(3)]
    facing = _cross(result, corners_of)
    length = np.sqrt(_dot(facing, facing))
    facing /= np.where(length > 0, length, 1.0)
    before = _cross(start, corners_of)
    least = np.maximum(FOLDED * _dot(before, facing), FLAT * np.sqrt(_dot(before, before)))
    least[length == 0] = -np.inf  # a smoothed triangle without area has no side to fold to
    checked = slice(None)
    share, away, at_vertex = None, None, None
    round_ = 0
    while True:
        picked = [column[checked] for column in corners_of]
        shadow = _dot(_cross(kept, picked), facing[:, checked])
        bound = least[checked]
        folded = (shadow <= 0.0) & (bound > -np.inf) | (shadow < bound)
        if share is not None:  # a triangle all of whose corners are back at the result stays as it is
            folded &= (share[picked[0]] > 0) | (share[picked[1]] > 0) | (share[picked[2]] > 0)
        folded = np.flatnonzero(folded)
        if folded.size == 0:
            return
        corners = np.zeros(len(kept), dtype=bool)
        for column in picked:
            corners[column[folded]] = True
        corners = np.flatnonzero(corners)
        if share is None:
            share, away = np.ones(len(kept)), kept - result
            at_vertex = _triangles_at(triangles, len(kept))
        round_ += 1
        share[corners] = 0.0 if round_ > _ROUNDS else 0.5 * share[corners]
        kept[corners] = result[corners] + share[corners, None] * away[corners]
        near = np.zeros(len(triangles), dtype=bool)
        near[at_vertex[corners].indices] = True
        checked = np.flatnonzero(near)


def _triangles_at(triangles, n):
    """(n, t) CSR: row v lists the triangles with corner v."""
    t = len(triangles)
    rows = triangles.ravel()
    columns = np.repeat(np.arange(t), 3)
    return sp.csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, columns)), shape=(n, t))


def _cross(points, corners_of):
    """(3, t) twice-area normals of the triangles whose corners are the index arrays ``corners_of``
    (a, b, c), over (n, 3) ``points``, float64, coordinate by coordinate."""
    planar = np.ascontiguousarray(points.T, dtype=np.float64)
    a, b, c = corners_of
    u = [row.take(b) - row.take(a) for row in planar]
    v = [row.take(c) - row.take(a) for row in planar]
    return np.stack((u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]))


def _dot(a, b):
    """Column-wise dot product of (3, t) arrays."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
