"""Keep the enclosed volume: move the smoothed vertices of each closed part a uniform distance along
their normals until the part encloses the volume it had before smoothing.

Every low-pass filter moves a curved surface towards its centres of curvature: HC far less than the
Laplacian, but where the noise is large against a thin part (a tube a few edges around) the smoothing
that removes it best also takes a few per cent of the part's volume. A uniform offset along the
normals gives that back without changing the shape's detail (unlike a scaling about a centre, which
moves far-away vertices most).

The volume of a part after an offset d along the (area-weighted, unit) vertex normals is a cubic in
d: its four coefficients per part come from one pass over the triangles, and Newton steps from d = 0
solve it.
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

_NEWTON_STEPS = 6  # at most; the volume is a cubic in the offset, Newton from 0 needs two or three
_RELATIVE_ACCURACY = 1e-12
_BLOCK = 1 << 18  # triangles per block: bounds the temporaries


def vertex_normals(positions, triangles):
    """Area-weighted unit vertex normals of a triangle mesh (zero where no face touches a vertex).

    Examples
    --------
    >>> import numpy as np
    >>> from core import volume
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> volume.vertex_normals(positions, triangles).round(3).tolist()
    [[-0.577, -0.577, -0.577], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    n = positions.shape[0]
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    face = _cross(b - a, c - a)
    normals = np.stack(
        [sum(np.bincount(triangles[:, k], weights=face[j], minlength=n) for k in range(3)) for j in range(3)], axis=1
    )
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0.0, length, 1.0)


def _cross(b, c):
    """Row-wise b x c of (k, 3) arrays, as three columns."""
    return (
        b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1],
        b[:, 2] * c[:, 0] - b[:, 0] * c[:, 2],
        b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0],
    )


def _det(a, b, c):
    x, y, z = _cross(b, c)
    return a[:, 0] * x + a[:, 1] * y + a[:, 2] * z


def _volume_cubics(positions, normals, triangles, part_of_triangle, parts, centre):
    """Per part, the coefficients (c0, c1, c2, c3) of its volume after an offset d along the normals:
    V(d) = c0 + c1 d + c2 d^2 + c3 d^3 (each triangle's signed tetrahedron volume is a cubic in d).
    ``normals`` None: the volume alone, (c0,)."""
    cubics = np.zeros((4 if normals is not None else 1, parts))
    for start in range(0, len(triangles), _BLOCK):
        block = triangles[start : start + _BLOCK]
        a, b, c = (positions[block[:, k]] - centre for k in range(3))
        owner = part_of_triangle[start : start + _BLOCK]
        if normals is None:
            cubics[0] += np.bincount(owner, weights=_det(a, b, c) / 6.0, minlength=parts)
            continue
        na, nb, nc = (normals[block[:, k]] for k in range(3))
        terms = (
            _det(a, b, c),
            _det(na, b, c) + _det(a, nb, c) + _det(a, b, nc),
            _det(na, nb, c) + _det(na, b, nc) + _det(a, nb, nc),
            _det(na, nb, nc),
        )
        for degree, term in enumerate(terms):
            cubics[degree] += np.bincount(owner, weights=term / 6.0, minlength=parts)
    return cubics


def restore_volume(before, after, triangles, movable=None):
    """``after`` with each closed part's enclosed volume set back to its volume in ``before``, by a
    uniform offset of that part's movable vertices along their normals. Returns (positions, offsets)
    with offsets the distance per part (same units as the positions).

    ``triangles`` (t, 3) of a closed, consistently oriented mesh; ``movable`` a boolean mask (default:
    every vertex). A part without movable vertices, or with no volume, is left as it is.

    Examples
    --------
    >>> import numpy as np
    >>> from core import metrics, volume
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> shrunk = 0.9 * positions + 0.025
    >>> restored, offsets = volume.restore_volume(positions, shrunk, triangles)
    >>> [round(float(metrics.enclosed_volume(p, triangles)), 4) for p in (positions, shrunk, restored)]
    [0.1667, 0.1215, 0.1667]
    >>> offsets.round(4).tolist()  # one part, moved this far along its normals
    [0.0642]
    """
    before = np.asarray(before, dtype=np.float64)
    result = np.array(after, dtype=np.float64)
    triangles = np.asarray(triangles)
    n = result.shape[0]
    if triangles.size == 0:
        return result, np.zeros(0)
    movable = np.ones(n, bool) if movable is None else np.asarray(movable, bool)
    pairs = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    graph = sp.coo_matrix((np.ones(len(pairs), np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    parts, part_of_vertex = connected_components(graph, directed=False)
    part_of_triangle = part_of_vertex[triangles[:, 0]]
    centre = before.mean(axis=0)
    target = _volume_cubics(before, None, triangles, part_of_triangle, parts, centre)[0]
    normals = vertex_normals(result, triangles) * movable[:, None]
    c0, c1, c2, c3 = _volume_cubics(result, normals, triangles, part_of_triangle, parts, centre)
    offsets = np.zeros(parts)
    for _ in range(_NEWTON_STEPS):
        d = offsets
        missing = target - (c0 + d * (c1 + d * (c2 + d * c3)))
        slope = c1 + d * (2.0 * c2 + 3.0 * d * c3)
        usable = (np.abs(slope) > 0.0) & (target != 0.0)
        if np.all(np.abs(np.where(usable, missing, 0.0)) <= _RELATIVE_ACCURACY * np.abs(target)):
            break
        offsets = offsets + np.where(usable, missing / np.where(usable, slope, 1.0), 0.0)
    return result + normals * offsets[part_of_vertex][:, None], offsets
