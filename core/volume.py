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

The offset gives back what smoothing took, a little, and nothing else: it is bounded. A part that
smoothing collapsed (too small to smooth, flattened: it kept less than KEPT of its volume) has a cubic
whose root lies far away or nowhere, and following it would blow the part up; such a part keeps its
smoothed shape. Only closed parts with more than DEGENERATE vertices and a volume are restored, each
on its own; no offset grows a part's bounding box by more than GROWTH, and a caller's ``limit`` bounds
it further (the mesh pipeline passes NOISE_OFFSETS times the estimated noise).
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

_NEWTON_STEPS = 6  # at most; the volume is a cubic in the offset, Newton from 0 needs two or three
_RELATIVE_ACCURACY = 1e-12
_SETTLED = 1e-6  # a root Newton left further than this (relative to the volume) is no root
_FLAT = 1e-6  # a part enclosing less than this times its box diagonal cubed has no volume to keep
DEGENERATE = 4  # parts of at most this many vertices have no volume worth keeping (a tetrahedron at most)
GROWTH = 0.01  # the most an offset may grow a part's bounding box, along any axis (relative)
KEPT = 0.5  # a part that kept less than this share of its volume collapsed: it is not restored
# The mesh pipeline's limit, in noise deviations: the offsets that give back what HC took measure 0.01-0.3
# noise deviations on dense meshes, up to 0.75 on a coarse tube (noise 0.2-1 edge lengths).
NOISE_OFFSETS = 1.0
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


def closed_parts(triangles, part_of_triangle, parts):
    """(parts,) bool: whether each part's triangles close a consistently oriented surface (every directed
    edge once, and its reverse once)."""
    heads = triangles.ravel().astype(np.int64)
    tails = np.roll(triangles, -1, axis=1).ravel().astype(np.int64)
    n = int(triangles.max()) + 1
    keys, counts = np.unique(heads * n + tails, return_counts=True)
    reverse = np.searchsorted(keys, tails * n + heads)
    found = keys[np.minimum(reverse, keys.size - 1)] == tails * n + heads
    good = found & (counts[np.searchsorted(keys, heads * n + tails)] == 1)
    good &= counts[np.minimum(reverse, keys.size - 1)] == 1
    bad = np.bincount(np.repeat(part_of_triangle, 3)[~good], minlength=parts)
    return bad == 0


def restore_volume(before, after, triangles, movable=None, limit=None):
    """``after`` with each closed part's enclosed volume set back to its volume in ``before``, by a
    uniform offset of that part's movable vertices along their normals, within bounds. Returns
    (positions, offsets) with offsets the distance per part (same units as the positions).

    ``triangles`` (t, 3), consistently oriented; ``movable`` a boolean mask (default: every vertex);
    ``limit`` the largest offset allowed (None: no limit but the bounding box's). A part is left as it
    is where it is open (not every edge in two faces, in opposite directions), has at most
    ``DEGENERATE`` vertices or no volume (nothing to give back), has no movable vertex, kept less than
    ``KEPT`` of its volume (collapsed), or where the volume has no root within reach (an offset that
    does not grow the volume, Newton that does not settle). An offset outwards never makes the part's
    bounding box more than ``GROWTH`` larger than its box in ``before`` along any axis; inwards it is
    at most half the part's thinnest side; either way at most ``limit``: a root beyond that is clipped
    to it.

    Examples
    --------
    >>> import numpy as np
    >>> from core import metrics, volume
    >>> positions = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    >>> triangles = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    >>> shrunk = 0.95 * positions  # an octahedron
    >>> restored, offsets = volume.restore_volume(positions, shrunk, triangles)
    >>> [round(float(metrics.enclosed_volume(p, triangles)), 4) for p in (positions, shrunk, restored)]
    [1.3333, 1.1432, 1.3333]
    >>> offsets.round(4).tolist()  # one part, moved this far along its normals
    [0.05]
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
    used = np.zeros(n, bool)
    used[triangles.ravel()] = True
    sizes = np.bincount(part_of_vertex[used], minlength=parts)
    low_before, high_before = _boxes(before, part_of_vertex, used, parts)
    low_after, high_after = _boxes(result, part_of_vertex, used, parts)
    extent = high_before - low_before
    centre = before.mean(axis=0)
    target = _volume_cubics(before, None, triangles, part_of_triangle, parts, centre)[0]
    normals = vertex_normals(result, triangles) * movable[:, None]
    c0, c1, c2, c3 = _volume_cubics(result, normals, triangles, part_of_triangle, parts, centre)
    # An offset d moves every vertex by at most |d|: outwards, each side of the box grows by at most 2 d.
    # Inwards the box does not grow; there half the part's thinnest side bounds d (it would turn inside out).
    outward = np.maximum(((1.0 + GROWTH) * extent - (high_after - low_after)).min(axis=1), 0.0) / 2.0
    inward = (high_after - low_after).min(axis=1) / 2.0
    if limit is not None:
        outward, inward = np.minimum(outward, float(limit)), np.minimum(inward, float(limit))
    has_movable = np.bincount(part_of_vertex[movable & used], minlength=parts) > 0
    eligible = closed_parts(triangles, part_of_triangle, parts) & (sizes > DEGENERATE) & has_movable
    eligible &= np.abs(target) > _FLAT * np.linalg.norm(extent, axis=1) ** 3
    eligible &= c1 > 0.0  # the volume grows as the surface moves along its normals
    # Smoothing that took more than half the volume collapsed the part (or turned it inside out): no
    # uniform offset mends that, and one that tried would balloon it. (Same sign as target: c0 / target.)
    eligible &= c0 * np.sign(target) > KEPT * np.abs(target)
    offsets = np.zeros(parts)
    for _ in range(_NEWTON_STEPS):
        d = offsets
        missing = target - (c0 + d * (c1 + d * (c2 + d * c3)))
        slope = c1 + d * (2.0 * c2 + 3.0 * d * c3)
        step = eligible & (slope > 0.0) & np.isfinite(missing)
        settled = np.abs(missing) <= _RELATIVE_ACCURACY * np.abs(target)
        if np.all(settled | ~step):
            break
        offsets = offsets + np.where(step & ~settled, missing / np.where(step, slope, 1.0), 0.0)
    missing = target - (c0 + offsets * (c1 + offsets * (c2 + offsets * c3)))
    # A root is sensible where Newton settled near it (the volume a cubic: from 0 it takes two or three steps).
    sensible = eligible & np.isfinite(offsets) & (np.abs(missing) <= _SETTLED * np.abs(target))
    offsets = np.where(sensible, np.clip(offsets, -inward, outward), 0.0)
    return result + normals * offsets[part_of_vertex][:, None], offsets


def _boxes(points, part_of_vertex, used, parts):
    """(low, high) corners of each part's bounding box, (parts, 3) each."""
    low = np.full((parts, 3), np.inf)
    high = np.full((parts, 3), -np.inf)
    np.minimum.at(low, part_of_vertex[used], points[used])
    np.maximum.at(high, part_of_vertex[used], points[used])
    empty = ~np.isfinite(low[:, 0])  # a part without triangles (a loose vertex) has no box
    low[empty] = high[empty] = 0.0
    return low, high
