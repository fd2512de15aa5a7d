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

from .adjacency import grouped_pairs
from .parts import parts as connected_parts
from .slices import to_end

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
_VERTEX_BLOCK = 1 << 19  # vertices per block
_ROW_BLOCK = 1 << 16  # vertices per block where each of their half-edges is compared (several int64 each)


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
    return to_end(_normal_steps(positions, np.asarray(triangles)))


def _normal_steps(positions, triangles):
    """vertex_normals in slices (yields between blocks of triangles): float64 (n, 3), whatever the
    positions' dtype, the face normals summed in float64 block by block."""
    n = positions.shape[0]
    normals = np.zeros((n, 3))
    for start in range(0, len(triangles), _BLOCK):
        block = triangles[start : start + _BLOCK]
        a, b, c = (_corner(positions, block, k) for k in range(3))
        face = _cross(b - a, c - a)
        del a, b, c
        for j in range(3):
            normals[:, j] += sum(np.bincount(block[:, k], weights=face[j], minlength=n) for k in range(3))
        yield
    for start in range(0, n, _VERTEX_BLOCK):
        rows = normals[start : start + _VERTEX_BLOCK]
        length = np.linalg.norm(rows, axis=1, keepdims=True)
        rows /= np.where(length > 0.0, length, 1.0)
    return normals


def _corner(positions, triangles, k, centre=None):
    """The float64 positions of corner k of each triangle (less ``centre``)."""
    corner = np.asarray(positions[triangles[:, k]], dtype=np.float64)
    if centre is not None:
        corner -= centre
    return corner


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


def _cubic_steps(before, after, normals, triangles, part_of_vertex, parts, centre):
    """(target, cubics) in slices: per part its volume in ``before``, (parts,), and the coefficients
    (c0, c1, c2, c3), (4, parts), of its volume after an offset d along ``normals`` from ``after``:
    V(d) = c0 + c1 d + c2 d^2 + c3 d^3 (each triangle's signed tetrahedron volume is a cubic in d)."""
    target = np.zeros(parts)
    cubics = np.zeros((4, parts))
    for start in range(0, len(triangles), _BLOCK):
        block = triangles[start : start + _BLOCK]
        owner = part_of_vertex[block[:, 0]]
        target += np.bincount(
            owner, weights=_det(*(_corner(before, block, k, centre) for k in range(3))) / 6.0, minlength=parts
        )
        a, b, c = (_corner(after, block, k, centre) for k in range(3))
        na, nb, nc = (normals[block[:, k]] for k in range(3))
        terms = (
            _det(a, b, c),
            _det(na, b, c) + _det(a, nb, c) + _det(a, b, nc),
            _det(na, nb, c) + _det(na, b, nc) + _det(a, nb, nc),
            _det(na, nb, nc),
        )
        for degree, term in enumerate(terms):
            cubics[degree] += np.bincount(owner, weights=term / 6.0, minlength=parts)
        yield
    return target, cubics


def _half_edges(triangles, n):
    """(indptr, tails): the triangles' half-edges h -> t (each corner to the next) as a CSR pattern, row
    h listing its tails increasing, duplicates kept."""
    index = np.int32 if n < np.iinfo(np.int32).max else np.int64
    heads = np.ascontiguousarray(triangles, dtype=index).ravel()
    tails = np.empty_like(heads)
    corners, nexts = heads.reshape(-1, 3), tails.reshape(-1, 3)
    nexts[:, :2], nexts[:, 2] = corners[:, 1:], corners[:, 0]
    del corners, nexts
    return grouped_pairs(heads, tails, n)


def _topology(triangles, n):
    """(parts, part_of_vertex, used, closed) of a triangle mesh: its connected parts (vertices linked
    through triangles; a vertex on no triangle is a part of its own), numbered by lowest vertex; the
    vertices on a triangle; per part whether its triangles close a consistently oriented surface
    (every directed edge once, and its reverse once). One counting sort of the half-edges: a vertex's
    outgoing half-edges, sorted, must equal its incoming ones and hold no pair twice."""
    indptr, tails = _half_edges(triangles, n)
    degree = np.diff(indptr)
    twice = np.zeros(tails.size, dtype=bool)  # a pair a row already has (sorted rows: the one before)
    np.equal(tails[1:], tails[:-1], out=twice[1:])
    twice[indptr[:-1][degree > 0]] = False  # a row's first entry follows another row's
    bad = np.zeros(n, dtype=bool)
    if twice.any():
        bad[np.searchsorted(indptr, np.flatnonzero(twice), side="right") - 1] = True
        pattern = sp.csr_matrix((np.ones(tails.size, np.int8), tails, indptr), shape=(n, n))
        pattern.sum_duplicates()  # SciPy's strong components do not finish on a pattern with a pair twice
        parts, part_of_vertex = connected_parts(pattern.indptr, pattern.indices, n, cyclic=True)
        del pattern
    else:  # every triangle is a cycle h -> t: the half-edges' strong components are the parts
        parts, part_of_vertex = connected_parts(indptr, tails, n, cyclic=True)
    del twice
    used = degree > 0
    transposed = sp.csr_matrix((np.ones(tails.size, np.int8), tails, indptr), shape=(n, n), copy=False).tocsc()
    incoming, heads = np.diff(transposed.indptr), transposed.indices  # row t: its heads, increasing
    bad |= degree != incoming
    for low in range(0, n, _ROW_BLOCK):
        high = min(n, low + _ROW_BLOCK)
        rows = np.arange(low, high)[~bad[low:high]]
        counts = degree[rows]
        offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        wrong = (
            tails[np.repeat(indptr[rows], counts) + offset]
            != heads[np.repeat(transposed.indptr[rows], counts) + offset]
        )
        bad[np.repeat(rows, counts)[wrong]] = True
    closed = np.bincount(part_of_vertex[bad], minlength=parts) == 0
    return parts, part_of_vertex, used, closed


def restore_volume(before, after, triangles, movable=None, limit=None):
    """``after`` with each closed part's enclosed volume set back to its volume in ``before``, by a
    uniform offset of that part's movable vertices along their normals, within bounds. Returns
    (positions, offsets) with positions float64 and offsets the distance per part (same units as the
    positions).

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
    return to_end(restore_steps(before, after, triangles, movable, limit))


def restore_steps(before, after, triangles, movable=None, limit=None, dtype=np.float64):
    """``restore_volume`` in slices, for callers that let the user cancel: a generator that yields (None)
    between its passes and returns (positions in ``dtype``, offsets); the same numbers (float64 math,
    cast to ``dtype`` at the end). Beside its result it holds the float64 normals and a few bytes a
    vertex: the positions are read in blocks, never copied whole."""
    before, after, triangles = np.asarray(before), np.asarray(after), np.asarray(triangles)
    n = after.shape[0]
    if triangles.size == 0:
        return np.array(after, dtype=dtype), np.zeros(0)
    movable = np.ones(n, bool) if movable is None else np.asarray(movable, bool)
    parts, part_of_vertex, used, closed = _topology(triangles, n)
    yield
    sizes = np.bincount(part_of_vertex[used], minlength=parts)
    low_before, high_before = _boxes(before, part_of_vertex, used, parts)
    low_after, high_after = _boxes(after, part_of_vertex, used, parts)
    extent = high_before - low_before
    centre = _centre(before)
    yield
    normals = yield from _normal_steps(after, triangles)
    normals *= movable[:, None]
    target, (c0, c1, c2, c3) = yield from _cubic_steps(before, after, normals, triangles, part_of_vertex, parts, centre)
    # An offset d moves every vertex by at most |d|: outwards, each side of the box grows by at most 2 d.
    # Inwards the box does not grow; there half the part's thinnest side bounds d (it would turn inside out).
    outward = np.maximum(((1.0 + GROWTH) * extent - (high_after - low_after)).min(axis=1), 0.0) / 2.0
    inward = (high_after - low_after).min(axis=1) / 2.0
    if limit is not None:
        outward, inward = np.minimum(outward, float(limit)), np.minimum(inward, float(limit))
    has_movable = np.bincount(part_of_vertex[movable & used], minlength=parts) > 0
    eligible = closed & (sizes > DEGENERATE) & has_movable
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
    result = np.empty((n, 3), dtype=dtype)
    for start in range(0, n, _VERTEX_BLOCK):
        rows = slice(start, start + _VERTEX_BLOCK)
        moved = np.asarray(after[rows], dtype=np.float64) + normals[rows] * offsets[part_of_vertex[rows]][:, None]
        result[rows] = moved
    return result, offsets


def _centre(points):
    """The mean of (n, 3) points, in float64."""
    if points.shape[0] <= _VERTEX_BLOCK:
        return np.asarray(points, dtype=np.float64).mean(axis=0)
    total = sum(
        np.asarray(points[start : start + _VERTEX_BLOCK], dtype=np.float64).sum(axis=0)
        for start in range(0, points.shape[0], _VERTEX_BLOCK)
    )
    return total / points.shape[0]


def _boxes(points, part_of_vertex, used, parts):
    """(low, high) corners of each part's bounding box, float64 (parts, 3) each."""
    low = np.full((parts, 3), np.inf)
    high = np.full((parts, 3), -np.inf)
    for start in range(0, points.shape[0], _VERTEX_BLOCK):
        rows = slice(start, start + _VERTEX_BLOCK)
        inside = used[rows]
        block, owner = np.asarray(points[rows][inside], dtype=np.float64), part_of_vertex[rows][inside]
        if owner.size and owner[0] == owner[-1] and np.all(owner == owner[0]):  # one part: a plain min and max
            low[owner[0]] = np.minimum(low[owner[0]], block.min(axis=0))
            high[owner[0]] = np.maximum(high[owner[0]], block.max(axis=0))
        elif owner.size:
            np.minimum.at(low, owner, block)
            np.maximum.at(high, owner, block)
    empty = ~np.isfinite(low[:, 0])  # a part without triangles (a loose vertex) has no box
    low[empty] = high[empty] = 0.0
    return low, high
