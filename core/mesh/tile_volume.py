"""Closed parts' volume given back in a mesh smoothed in tiles (files: cli/tiled.py): core.mesh.volume's
restore, with its sums over each part gathered tile by tile.

The restore moves each closed part's vertices a uniform offset along their normals; the offset solves a
cubic whose coefficients are sums over the part's triangles (core.mesh.volume). Those sums add up over any
split of the triangles, so each tile adds the triangles it *owns* (those whose first corner is its own
vertex: every triangle once) to the piece of each part it holds (``TiledVolume.add_tile``); the pieces meet
in their parts once every tile is done, and each part's offset is solved once (``TiledVolume.solve``), with
core.mesh.volume's own rules and bounds. A second pass over the tiles moves each tile's vertices
(``TiledVolume.restored``): their normals read the smoothed positions of their 1-ring only.

**Parts.** Which vertices form a part is a question about the whole mesh: ``PartUnion`` answers it with one
index per vertex (a union-find), joined tile by tile. A tile's own part pieces are connected, and every edge
of the mesh lies inside the tile that owns one of its ends, with that end's whole 1-ring, so joining each
tile's pieces makes the parts of the whole mesh (welded, as each tile welds its copies). A part is closed
where none of its vertices has a half-edge without a single reverse (core.mesh.topology's ``unmatched``): a
vertex's own triangles decide that, and the tile that owns the vertex holds them all.

**The same offsets.** A tile's own triangles and the normals at their corners read the smoothed positions
within two rings of its own vertices, which the halo holds exactly (core.tile_rings with ``volume``): the
sums are the whole run's, added in another order (to rounding), and so are the offsets.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..geometry import index_dtype, normals_and_measures, project_rows_within
from ..slices import to_end
from . import topology, volume


class PartUnion:
    """The parts of a mesh of ``n`` vertices, joined piece by piece (``join``): a union-find over the
    vertices, one index a vertex, every vertex pointing at a lower-numbered one or itself (its part's root).

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh.tile_volume import PartUnion
    >>> union = PartUnion(6)
    >>> union.join(np.array([4, 5, 1, 2]), np.array([0, 0, 1, 1]))  # {4, 5}, {1, 2}
    >>> union.join(np.array([2, 5]), np.array([0, 0]))  # and 2 with 5
    >>> union.find(np.arange(6)).tolist()
    [0, 1, 1, 3, 1, 1]
    """

    def __init__(self, n):
        self.parent = np.arange(n, dtype=index_dtype(n))

    def find(self, vertices):
        """The roots of ``vertices`` (their paths are shortened to point at them)."""
        roots = self.parent[vertices]
        while True:
            up = self.parent[roots]
            if np.array_equal(up, roots):
                break
            roots = up
        self.parent[vertices] = roots
        return roots

    def join(self, vertices, groups):
        """Join each vertex of ``vertices`` with the others of its group (``groups``: a label per vertex,
        0 to g - 1): the groups and the roots they reach are linked, and each linked set takes its lowest
        root."""
        if len(vertices) == 0:
            return
        roots, at = np.unique(self.find(vertices), return_inverse=True)
        count = int(groups.max()) + 1
        links = sp.coo_matrix(
            (np.ones(len(vertices), np.int8), (groups, count + at.ravel())), shape=(count + len(roots),) * 2
        )
        _, labels = connected_components(links, directed=False)
        lowest = np.full(labels.max() + 1, len(self.parent), dtype=np.int64)
        np.minimum.at(lowest, labels[count:], roots)
        self.parent[roots] = lowest[labels[count:]]


@dataclass
class _Pieces:
    """Per piece of a part a tile holds: a vertex of it (its root found later), whether an own vertex is
    unmatched (the part is open) or movable, its own used vertices, the sums over its own triangles
    (volume before, c0, area, c1, c2, c3; times 6 or 2 as core.mesh.volume keeps them) and the boxes of its
    own used vertices before and after smoothing (low, high, low after, high after)."""

    vertex: np.ndarray
    unmatched: np.ndarray
    movable: np.ndarray
    sizes: np.ndarray
    sums: np.ndarray  # (k, 6)
    boxes: np.ndarray  # (k, 12)


@dataclass
class TilePiece:
    """What a smoothed tile adds to a ``TiledVolume``: its vertices (mesh indices) ``joined`` with the others
    of their ``groups`` (the union's links) and the ``pieces`` of the parts it holds."""

    joined: np.ndarray
    groups: np.ndarray
    pieces: _Pieces


class TiledVolume:
    """The volume restore of a mesh of ``n`` vertices smoothed in tiles (see the module docstring):
    ``add_tile`` after each tile's smoothing, ``solve`` once, ``restored`` for each tile of the second pass.
    ``noise``: the noise the Automatic Amount found (the offsets reach at most core.mesh.volume.NOISE_OFFSETS
    times it, as in the mesh pipeline), ``deviation``: the run's deviation limit, which the moved vertices
    keep to as the whole run's do; ``centre``: where the volumes are measured from (a point near the mesh);
    ``most_pieces``: the most pieces of parts kept (PIECE_BYTES each) before the restore gives up (``too_many``:
    no offsets then, each tile stays as smoothed).

    Examples
    --------
    An octahedron smoothed as one tile, its triangles added by two tiles that own half its vertices each:

    >>> import numpy as np, core
    >>> from core.mesh import metrics
    >>> positions = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    >>> triangles = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    >>> edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    >>> run = core.MeshSmoother(positions, edges, faces=triangles, alpha=0.0, beta=0.9, iterations=1, weld=True)
    >>> smoothed = run.run()
    >>> restore = core.TiledVolume(6, noise=1.0, deviation=0.0, centre=np.zeros(3))
    >>> for own in (positions[:, 0] >= 0, positions[:, 0] < 0):
    ...     restore.add_tile(run, np.arange(6), own)
    >>> round(restore.solve(), 4), restore.restored_parts  # the offset core.mesh.volume finds on the whole
    (0.1, 1)
    >>> restored = restore.restored(run, smoothed, np.arange(6))
    >>> [round(float(metrics.enclosed_volume(p, triangles)), 4) for p in (positions, smoothed, restored)]
    [1.3333, 0.972, 1.3333]
    """

    # What a piece of a part costs until the offsets are solved (its vertex, flags, count, sums, boxes), twice
    # while they are joined.
    PIECE_BYTES = 2 * (8 + 2 + 8 + 6 * 8 + 12 * 8)

    def __init__(self, n, noise, deviation, centre, most_pieces=None):
        self.most_pieces, self.too_many = most_pieces, False
        self.union = PartUnion(n)
        self.limit = volume.NOISE_OFFSETS * float(noise)
        self.deviation, self.centre = deviation, np.asarray(centre, np.float64)
        self.pieces, self.piece_count = [], 0
        self.roots = self.offsets = None
        self.volume_before = self.restored_parts = 0

    def add_tile(self, run, vertices, own):
        """Add a smoothed tile: ``run`` the core.MeshSmoother that smoothed it (its welding, faces and fixed
        vertices), ``vertices`` its vertices' indices in the mesh, ``own`` which are the tile's own. Only the
        triangles around its own vertices and around the corners of its own triangles are read."""
        if not self.too_many:
            self.add(self.piece(run, vertices, own, self.centre))

    @staticmethod
    def piece(run, vertices, own, centre):
        """What ``add_tile`` adds (its arguments, ``centre`` the TiledVolume's), made where the tile ran (a
        worker too): a ``TilePiece``, or None where the tile has no triangles."""
        if run.faces is None or len(run.faces) == 0:
            return None
        welded = len(run.positions)
        first = run.welding.first if run.welding is not None else np.arange(welded)
        label = run.welding.label if run.welding is not None else np.arange(welded)
        own = np.asarray(own, bool)[first]
        near, triangles = _around_own(run.faces, own)
        at = np.full(welded, -1, dtype=np.int64)
        at[near] = np.arange(len(near))
        own, movable, copies = own[near], _movable(run)[near], np.flatnonzero(at[label] >= 0)
        surface = topology.surface(triangles, len(near))
        parts, part_of_vertex = surface.parts, surface.part_of_vertex
        owned = own & surface.used
        counted = np.bincount(part_of_vertex[owned], minlength=parts) > 0  # the pieces this tile adds
        groups = part_of_vertex[at[label[copies]]]
        owner = np.where(own, part_of_vertex, parts)  # only own triangles and vertices count: the rest is ``parts``
        planar_before, planar_after = volume.as_planar(run.positions[near]), volume.as_planar(run.result[first[near]])
        target = to_end(volume.volume_steps(planar_before, triangles, owner, parts + 1, centre))
        normals, (c0, area) = to_end(
            normals_and_measures(planar_after, triangles, owner, parts + 1, centre, volume.BLOCK)
        )
        normals *= movable
        mine = triangles[own[triangles[:, 0]]]  # the cubic's terms of the other triangles go to part ``parts``
        cubic = to_end(volume.cubic_steps(planar_after, normals, mine, owner, parts + 1, centre))
        rows = np.flatnonzero(owned)
        boxes = [
            *volume.part_boxes(planar_before[:, rows], owner[rows], np.ones(len(rows), bool), parts + 1),
            *volume.part_boxes(planar_after[:, rows], owner[rows], np.ones(len(rows), bool), parts + 1),
        ]
        lowest = np.full(parts, len(near), dtype=np.int64)
        np.minimum.at(lowest, part_of_vertex, np.arange(len(near)))
        keep = np.flatnonzero(counted)
        pieces = _Pieces(
            vertex=vertices[first[near[lowest[keep]]]],
            unmatched=(np.bincount(owner[surface.unmatched & own], minlength=parts + 1) > 0)[keep],
            movable=(np.bincount(owner[owned & movable], minlength=parts + 1) > 0)[keep],
            sizes=np.bincount(owner[owned], minlength=parts + 1)[keep],
            sums=np.stack([target, c0, area, *cubic], axis=1)[keep],
            boxes=np.concatenate(boxes, axis=1)[keep],
        )
        return TilePiece(vertices[copies[counted[groups]]], groups[counted[groups]], pieces)

    def add(self, piece):
        """Add a tile's ``TilePiece`` (``piece``), in any order."""
        if self.too_many or piece is None:
            return
        self.union.join(piece.joined, piece.groups)
        self.pieces.append(piece.pieces)
        self.piece_count += len(piece.pieces.vertex)
        if self.most_pieces is not None and self.piece_count > self.most_pieces:
            self.too_many, self.pieces = True, []

    def solve(self):
        """Each part's offset from the sums of its pieces (core.mesh.volume's rules and bounds); returns the
        largest offset (0: none)."""
        if self.too_many or not self.pieces:
            self.roots, self.offsets = np.zeros(0, dtype=np.int64), np.zeros(0)
            return 0.0
        pieces = _Pieces(*(np.concatenate([getattr(p, name) for p in self.pieces]) for name in _Pieces.__annotations__))
        self.pieces = []
        roots, at = np.unique(self.union.find(pieces.vertex), return_inverse=True)
        at = at.ravel()
        sums = np.stack([np.bincount(at, weights=column, minlength=len(roots)) for column in pieces.sums.T])
        target, c0, area, c1, c2, c3 = sums
        low, high, low_after, high_after = (np.full((len(roots), 3), np.inf * sign) for sign in (1, -1, 1, -1))
        for box, column, least in ((low, 0, True), (high, 3, False), (low_after, 6, True), (high_after, 9, False)):
            for j in range(3):
                (np.minimum if least else np.maximum).at(box[:, j], at, pieces.boxes[:, column + j])
        closed = np.bincount(at, weights=pieces.unmatched, minlength=len(roots)) == 0
        movable = np.bincount(at, weights=pieces.movable, minlength=len(roots)) > 0
        sizes = np.bincount(at, weights=pieces.sizes, minlength=len(roots))
        extent = high - low
        outward, inward = volume.offset_bounds(extent, high_after - low_after, self.limit)
        eligible = volume.eligible_parts(closed & movable, sizes, target, extent, c0, area, self.limit)
        offsets = volume.solve_offsets(target, (c0, c1, c2, c3), eligible, inward, outward)
        moving = offsets != 0.0
        self.roots, self.offsets = roots[moving], offsets[moving]
        self.restored_parts = int(np.count_nonzero(moving))
        return float(np.abs(offsets).max())

    def restored(self, run, after, vertices):
        """(m, 3) the tile's positions with the offsets: ``run`` a core.MeshSmoother of the tile's input,
        prepared (``still()``: welded, the border rule applied), ``after`` the smoothed positions of its
        vertices (in the precision it ran in), ``vertices`` their indices in the mesh. Moved as the whole
        run moves them (core.mesh.volume.restore_steps, then kept within the deviation limit); right where
        the tile holds a vertex's 1-ring."""
        after = np.asarray(after)
        welded = len(run.positions)
        first = run.welding.first if run.welding is not None else np.arange(welded)
        smoothed = after[first]
        if run.faces is None or len(run.faces) == 0 or self.roots.size == 0:
            return after
        roots = self.union.find(vertices[first])
        at = np.minimum(np.searchsorted(self.roots, roots), len(self.roots) - 1)
        offsets = np.where(self.roots[at] == roots, self.offsets[at], 0.0)
        normals, _ = to_end(
            normals_and_measures(
                volume.as_planar(smoothed), run.faces, None, 1, self.centre, volume.BLOCK, measure=False
            )
        )
        movable = _movable(run)
        normals *= movable
        result = volume.moved_along(smoothed, normals, offsets).astype(after.dtype)
        result[~movable] = smoothed[~movable]
        if np.any(self.deviation):
            project_rows_within(result, run.positions, self.deviation)
        return result if run.welding is None else run.welding.scatter(result)


def tile_volumes(before, after, triangles, own, centre):
    """(volume before, volume after, open) of a tile's own triangles (their first corner its own; times 6,
    about ``centre``) on (m, 3) positions ``before`` and ``after``, and whether one of its ``own`` vertices
    has a half-edge without its single reverse (the mesh is open): summed over the tiles, what the whole
    run's report measures of the whole mesh (core.measure_change).

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh.tile_volume import tile_volumes
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])  # a tetrahedron, owned in two tiles
    >>> halves = [tile_volumes(positions, 2 * positions, triangles, own, np.zeros(3))
    ...           for own in ([1, 1, 0, 0], [0, 0, 1, 1])]
    >>> [float(sum(half[k] for half in halves)) for k in (0, 1)], any(half[2] for half in halves)
    ([1.0, 8.0], False)
    """
    own = np.asarray(own, bool)
    if len(triangles) == 0:
        return 0.0, 0.0, False
    label = np.where(own, 0, 1).astype(np.int32)
    volumes = [
        to_end(volume.volume_steps(volume.as_planar(p), triangles, label, 2, centre))[0] for p in (before, after)
    ]
    unmatched = topology.surface(triangles, len(own)).unmatched
    return float(volumes[0]), float(volumes[1]), bool(np.any(unmatched & own))


def _around_own(triangles, own):
    """(near, triangles): the (t, 3) ``triangles`` that touch an ``own`` vertex or a corner of a triangle whose
    first corner is own (so that those vertices' normals are whole), renumbered onto ``near``, the vertices
    they use (increasing: their order kept)."""
    corner = own.copy()
    corner[triangles[own[triangles[:, 0]]]] = True
    needed = triangles[corner[triangles].any(axis=1)]
    near = np.unique(needed)
    return near, np.searchsorted(near, needed).astype(triangles.dtype)


def _movable(run):
    """The welded vertices the restore moves: neither fixed (the border rule's too) nor of influence 0."""
    return ~run.fixed if run.influence is None else ~run.fixed & (run.influence > 0.0)
