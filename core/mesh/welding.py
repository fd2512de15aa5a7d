"""Split vertices smoothed as one: UV seams, flat-shaded triangle soups, STL files.

Files and exporters split a vertex wherever something other than its position differs between its
faces (UV, normal, colour), and a triangle soup (STL, flat-shaded PLY) gives every face its own three
vertices. To the smoother such copies are unconnected: each sees only its own faces' neighbours, a
seam opens into a crack, and a soup's vertices, each with two neighbours, collapse. Welded, they are
one vertex of one surface.

``weld`` finds the coincident vertices (equal positions always; within ``TOLERANCE`` x the median edge
length too) and returns a ``Welding``: the map from each vertex to its welded vertex (numbered in the
order of their first copies), with which the mesh's operator, faces, fixed mask and influence are
mapped onto the welded vertices, and the smoothed welded positions scattered back. The caller's mesh
keeps its vertices: every copy gets its welded vertex's move.

Finding them costs a pass of a hash table and one sort: points are put into cells of CELL_EDGES x the
median edge length, and only those whose cell key shares a slot of the table with another's (or that lie
within the tolerance of a cell's side) are sorted by key; copies in a cell where every point is equal
are welded at once, and only the few points that share a cell with a different point, or lie within the
tolerance of a cell's side, go through a k-d tree (scipy.spatial.cKDTree.query_pairs) and a union of the
pairs (connected components).

Examples
--------
Two triangles of a soup sharing an edge by position only: smoothed welded, the copies move alike.

>>> import numpy as np, core
>>> soup = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.2], [1, 0, 0], [1, 1, 0], [0, 1, 0.2]])
>>> faces = [[0, 1, 2], [3, 4, 5]]
>>> edges = [[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3]]
>>> result = core.smooth_mesh(soup, edges, faces=faces, weld=True, alpha=0.1, beta=0.6, iterations=3)
>>> bool(np.array_equal(result[1], result[3]) and np.array_equal(result[2], result[5]))
True
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .. import parallel
from ..adjacency import Umbrella, umbrella_from_pairs
from ..geometry import median_edge_length
from ..parallel import BLOCK
from ..slices import to_end

TOLERANCE = 1e-6  # vertices closer than this times the median edge length are one (equal ones always)
CELL_EDGES = 1 / 8  # cell side in median edge lengths: distinct vertices rarely share a cell
_FINEST_CELL = 2.0**-40  # cell side at least this times the bounding-box diagonal (keys fit in int64)
_PACKED_BITS = 21  # cell coordinates below 2**21 per axis are packed into a key exactly
_SLOT_BITS = 23  # the hash table that screens the keys: 8M slots at most (64 MB of counts)
_MIX = 0x9E3779B97F4A7C15  # Fibonacci hashing: the key times 2**64 / golden ratio, its top bits the slot
_ROWS = BLOCK  # vertices per block of the cell keys (float64 and int64 temporaries: a few MB a thread)


@dataclass(frozen=True)
class Welding:
    """Vertex i of the mesh is welded vertex ``label[i]``; welded vertex k starts at the position of its
    lowest-numbered copy ``first[k]``. ``near``: the copies whose own position differs from that (within
    the tolerance), which keep their offset from it."""

    label: np.ndarray
    first: np.ndarray
    near: np.ndarray
    start: np.ndarray  # the mesh's positions (not copied)

    @property
    def count(self):
        return self.first.size

    def positions(self):
        return self.start[self.first]

    def operator(self, operator: Umbrella) -> Umbrella:
        """The umbrella of the welded vertices: every edge mapped through the map, self-loops dropped."""
        rows, columns = self.label[operator.rows()], self.label[operator.indices]
        return umbrella_from_pairs(rows, columns, self.count, symmetric=operator.symmetric or None)

    def triangles(self, triangles):
        """The (t, 3) triangles on the welded vertices, those that collapse to an edge or a point dropped."""
        welded = self.label[triangles]
        proper = (welded[:, 0] != welded[:, 1]) & (welded[:, 1] != welded[:, 2]) & (welded[:, 2] != welded[:, 0])
        return welded[proper]

    def fixed(self, fixed):
        """A welded vertex is fixed if any of its copies is."""
        return np.bincount(self.label, weights=fixed, minlength=self.count) > 0

    def influence(self, influence):
        """The least influence of a welded vertex's copies: no copy moves by more than its own weight
        lets it (a copy of weight 0 keeps its welded vertex, so itself, bit for bit)."""
        if influence is None:
            return None
        least = np.ones(self.count, dtype=influence.dtype)
        np.minimum.at(least, self.label, influence)
        return least

    def scatter(self, welded):
        """The mesh's positions from the welded vertices' ``welded`` positions: every copy moves as its
        welded vertex did; a copy whose welded vertex stayed keeps its own position bit for bit."""
        result = welded[self.label]
        if self.near.size:
            offset = self.start[self.near] - self.start[self.first[self.label[self.near]]]
            result[self.near] += offset
            stayed = np.all(welded == self.start[self.first], axis=1)[self.label[self.near]]
            result[self.near[stayed]] = self.start[self.near[stayed]]
        return result


def weld(positions, operator: Umbrella, tolerance: float = TOLERANCE) -> Welding | None:
    """The Welding of the coincident vertices of a mesh (its (n, 3) ``positions`` and umbrella
    ``operator``), or None when no two vertices coincide. ``tolerance``: in median edge lengths."""
    return to_end(weld_steps(positions, operator, tolerance))


def weld_steps(positions, operator: Umbrella, tolerance: float = TOLERANCE):
    """``weld`` in slices, for callers that let the user cancel: a generator that yields (None) between
    its passes and returns the Welding (or None)."""
    points = np.asarray(positions)
    labels = yield from _coincident(points, median_edge_length(points, operator), tolerance)
    if labels is None:
        return None
    count = int(labels.max()) + 1
    first = np.full(count, points.shape[0], dtype=np.int64)
    np.minimum.at(first, labels, np.arange(points.shape[0]))
    # Welded vertices numbered in the order of their first copies (a sequential run keeps its order).
    rank = np.empty(count, dtype=np.int64)
    order = np.argsort(first, kind="stable")
    rank[order] = np.arange(count)
    label, first = rank[labels], first[order]
    near = np.flatnonzero(np.any(points != points[first[label]], axis=1))
    return Welding(label=label, first=first, near=near, start=points)


def _coincident(points, edge, tolerance):
    """A generator (yields once, between the cell keys and their sort) returning per vertex a label
    shared by the coincident ones (equal, or within ``tolerance`` x ``edge`` through a chain of such
    pairs), or None when every vertex stands alone."""
    n = points.shape[0]
    if n < 2:
        return None
    low = np.array([points[:, k].min() for k in range(3)], dtype=np.float64)  # per column: 3x an axis-0 min
    high = np.array([points[:, k].max() for k in range(3)], dtype=points.dtype)
    extent = high - low
    diagonal = float(np.sqrt(np.dot(extent, extent)))
    if diagonal == 0.0:
        return np.zeros(n, dtype=np.int64)  # every vertex in one place
    radius = tolerance * edge
    side = max((edge or diagonal * 2.0**-20) * CELL_EDGES, diagonal * _FINEST_CELL, 2.0 * radius)
    # Each point's cell key, and whether it lies within the radius of its cell's side, in blocks of rows.
    packed = np.floor((high - low) / side).max() < 1 << _PACKED_BITS
    key = np.empty(n, dtype=np.int64)
    near = np.zeros(n, dtype=bool)
    margin = 2.0 * radius / side

    def keys(start, stop):  # element-wise: the blocks run on the threads
        scaled = (points[start:stop] - low) / side
        cells = np.floor(scaled).astype(np.int64)
        key[start:stop] = _cell_keys(cells, packed)
        if radius > 0.0:
            fraction = scaled - cells
            off = (fraction < margin) | (fraction > 1.0 - margin)  # within the margin of a side
            near[start:stop] = off[:, 0] | off[:, 1] | off[:, 2]

    parallel.run_chunks(keys, n, _ROWS)
    yield
    # Only vertices that share a slot of a hash table of the cell keys with another vertex, or lie within
    # the radius of their cell's side, may coincide: the sort takes those alone (on most meshes a few
    # slots are shared by chance, and nothing coincides).
    shared = _shared_slots(key)
    if radius > 0.0:
        shared |= near
    subset = np.flatnonzero(shared)
    del shared
    if subset.size < 2:
        return None
    group = _groups(key[subset], points[subset], near[subset] if radius > 0.0 else None, radius)
    if group is None:
        return None
    labels = np.empty(n, dtype=np.int64)
    labels[subset] = group
    alone = np.ones(n, dtype=bool)
    alone[subset] = False
    labels[alone] = int(group.max()) + 1 + np.arange(n - subset.size)
    return labels


def _groups(key, points, near, radius):
    """Per point (``key``: its cell's, ``near``: whether it lies within ``radius`` of its cell's side, or
    None) a label shared by the coincident ones, or None when every point stands alone."""
    n = points.shape[0]
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    key = None
    same_cell = sorted_key[1:] == sorted_key[:-1]
    del sorted_key
    sorted_points = points[order]
    same = sorted_points[1:] == sorted_points[:-1]
    equal = same_cell & same[:, 0] & same[:, 1] & same[:, 2]
    del same
    run = np.concatenate(([0], np.cumsum(~same_cell)))  # cell run of each sorted vertex
    # Points in a run with a different point, and points within the radius of a side of their cell, are
    # the only ones that may coincide with more than their equal neighbours in the sorted order.
    mixed_run = np.zeros(run[-1] + 1, dtype=bool)
    mixed_run[run[1:][same_cell & ~equal]] = True
    candidate = mixed_run[run]
    del run, same_cell
    if near is not None:
        candidate |= near[order]
    candidate = np.flatnonzero(candidate)
    pairs = np.empty((0, 2), dtype=np.int64)
    if candidate.size > 1:
        pairs = candidate[cKDTree(sorted_points[candidate]).query_pairs(radius, output_type="ndarray")]
    if not equal.any() and pairs.size == 0:
        return None
    if pairs.size == 0:  # a run of equal points in the sorted order is one vertex
        group = np.concatenate(([0], np.cumsum(~equal)))
    else:  # sorted vertex j joins j - 1 where they are equal, and the pairs the tree found join
        joined = np.flatnonzero(equal) + 1
        heads = np.concatenate((joined, pairs[:, 0]))
        tails = np.concatenate((joined - 1, pairs[:, 1]))
        graph = sp.coo_matrix((np.ones(heads.size, dtype=np.int8), (heads, tails)), shape=(n, n))
        group = connected_components(graph, directed=False)[1]
    labels = np.empty(n, dtype=np.int64)
    labels[order] = group
    return labels


def _shared_slots(key):
    """(n,) bool: the keys whose slot of a hash table (about four slots a key, 2**_SLOT_BITS at most) holds
    another key too: every key that occurs twice, and a few that meet by chance."""
    bits = min(_SLOT_BITS, max(1, int(np.ceil(np.log2(4 * key.size)))))
    with np.errstate(over="ignore"):
        slot = (key.view(np.uint64) * np.uint64(_MIX)) >> np.uint64(64 - bits)
    slot = slot.astype(np.intp)
    return np.bincount(slot, minlength=1 << bits)[slot] > 1


def _cell_keys(cells, packed):
    """One int64 per cell: ``packed`` exactly (every cell coordinate below 2**21), else a hash (cells that
    share a hash only make more candidates for the tree, never a wrong weld)."""
    if packed:
        return (cells[:, 0] << (2 * _PACKED_BITS)) | (cells[:, 1] << _PACKED_BITS) | cells[:, 2]
    with np.errstate(over="ignore"):
        return (
            cells[:, 0] * np.int64(73_856_093) ^ cells[:, 1] * np.int64(19_349_663) ^ cells[:, 2] * np.int64(83_492_791)
        )
