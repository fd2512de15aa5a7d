"""Keep in Place: each vertex moves across the surface, never along it.

A smoother's move of a vertex has two parts: one along the surface's normal, which removes the noise
that scanners put there, and one along the surface (the *slide*), which removes no noise but moves what
the vertex carries (a texture's point, a UV, an outline's place): a uniform umbrella pulls vertices
towards the centre of their neighbours, so irregular scans drift and open borders pull in.

``keep_in_place`` keeps only the first part: the input position plus the move's component along the
result's unit vertex normal. The vertex then lies on the smoothed surface's tangent plane at the place
the smoother took it to, over its input. A vertex on a crease of the result (its faces face two ways,
three at a corner: see CREASE) keeps its move in every direction its faces face and gives up only the
part along the crease. It runs once, after the iterations: projecting every
iteration's move instead leaves the mesh as irregular as the noise made it, and the umbrella's normal
component on an irregular mesh brings bumps back (bench/bench_keep_in_place.py, docs/keep_in_place.md).

An open border's vertex has its surface on one side only: its slide is the pull into the surface that
shrinks outlines and holes. Kept in place it does not slide; where keeping folds the layout (noise along
the surface larger than the edges) and its corners take their slide back, an outline vertex (on exactly
two border edges) takes back only the move across its border curve that smoothing the border as a curve
makes (the same smoother on the border edges alone, core.mesh.borders' ``"curve"`` rows), never longer than
the smoother's whole move of that vertex: the outline loses its jaggies there and keeps its place, size and
shape. Where nothing folds, an outline keeps its jaggies across the curve: a scan's outline is ragged in its
own right, and smoothing it as a curve would take that away.

Where the input's own layout on the surface is folded (noise along the surface larger than the edges),
or large moves along turning normals would fold it, a triangle kept in place would overlap its
neighbours; its corners take back part of the smoother's slide, as much as unfolds it.
"""

from dataclasses import dataclass
from functools import partial

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .. import parallel
from ..geometry import (
    SYMMETRIC_ENTRIES,
    cross,
    dot,
    index_dtype,
    smallest_eigenvectors,
    symmetric_eigenvalues,
    vertex_normal_steps,
)
from ..memory import small_pages
from ..parallel import BLOCK, VECTOR_BLOCK
from ..slices import to_end
from .noise import neighbours

# A kept triangle is flattened where its shadow on the smoothed surface is under FOLDED times its input's
# shadow, or under FLAT times its input's area (folded where the shadow is not positive).
FOLDED = 0.25
FLAT = 0.1
# How the corners of such triangles take their slide back: half of what is left for each of the first
# _ROUNDS rounds, where at most _HALVED of the triangles fold at first; all of it at once where more do;
# every vertex at once where more than _FOLDED_LAYOUT do (noise folded the layout). _LAST rounds at most.
_ROUNDS = 2
_HALVED = 0.1
_FOLDED_LAYOUT = 0.25
_LAST = 8
_BLOCK = BLOCK  # triangles per block of the first check: bounds the temporaries
# A vertex whose smoothed faces face more than one way keeps its move in every direction they face, and
# gives up only the part along its crease: the middle eigenvalue of its faces' normal tensor (area-weighted
# mean of n n^T, eigenvalues summing to 1) at least CREASE (sin^2 of half the angle between two equal faces:
# some 73 degrees), a corner (the smallest at least CORNER: three faces of a box's corner give 1/3) keeps all
# of it. Projected on the vertex normal alone, a crease vertex would keep the noise its faces' bisector does
# not see: on a coarse box half of it on every crease vertex. CREASE lies between the creases HC leaves
# rounded on a dense box (0.25-0.33) and those of a coarse one (7 cuts: 0.38-0.44); smoothed scans reach it
# at a few vertices (the cow at 0.25 % noise: 18-39 of 2,903; the face scan 2-7 of 85,182).
CREASE = 0.35
CORNER = 0.1


def keep_in_place(start: np.ndarray, result: np.ndarray, triangles: np.ndarray, outline=None) -> np.ndarray:
    """``result`` with each vertex's move from ``start`` reduced to its part along ``result``'s vertex
    normal (area-weighted, core.geometry.vertex_normals). Vertices in no triangle (no normal) keep their
    result, and the corners of a triangle that keeping would fold or flatten take back part of the slide
    (see ``unfold_steps``); a vertex that did not move stays bit for bit. ``outline``: an ``Outline`` (the border
    curves smoothed as curves, see ``outline_curves``) whose vertices also take the move across their
    curve. Returns a new array in ``result``'s dtype.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh.in_place import keep_in_place
    >>> start = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.1]])
    >>> result = start + [[0, 0, 0], [0, 0, 0], [0, 0, 0], [-0.2, -0.2, -0.1]]  # slid and lowered
    >>> keep_in_place(start, result, np.array([[0, 1, 3], [0, 3, 2]])).round(3).tolist()[3]
    [1.0, 1.0, 0.0]
    """
    return to_end(keep_in_place_steps(start, result, triangles, outline))


def keep_in_place_steps(start, result, triangles, outline=None, with_normals=False):
    """``keep_in_place`` in slices, for callers that show progress and let the user cancel: a generator
    that yields (None) between its passes (a round of blocks of triangles of the vertex normals, the
    projection, the crease rule, the fold check and each of its rounds) and returns the kept positions;
    ``with_normals``: (the kept positions, the (3, n) float64 unit vertex normals of ``result`` they were
    kept along), for a caller that offsets the kept surface along them (core.mesh.volume's restore).
    NumPy's huge-page request stays off (core.memory) until it ends or is closed, suspended or not."""
    with small_pages():  # its arrays are made once and read in order (core.memory)
        kept, normals = yield from _keep_in_place(start, result, triangles, outline)
    return (kept, normals) if with_normals else kept


def _keep_in_place(start, result, triangles, outline):
    """``keep_in_place_steps``' work: the projection a block of vertices at a time (no (n, 3) temporaries)."""
    triangles = np.asarray(triangles)
    corners_of = [np.ascontiguousarray(triangles[:, k], dtype=index_dtype(len(start))) for k in range(3)]
    # The unit normals and their agreement; the result's unit face normals and twice-areas from the same
    # products, for the crease rule and the fold check.
    facing, area = np.empty((3, len(triangles)), dtype=np.float32), np.empty(len(triangles), dtype=np.float32)
    rows = yield from vertex_normal_steps(result, triangles, agreement=True, faces=(facing, area))
    kept = np.empty(np.shape(result), dtype=result.dtype)  # worked in float64, kept as the result will be
    still = np.empty(len(kept), dtype=bool)
    parallel.run_chunks(partial(_projected, start, result, rows, kept, still), len(kept), VECTOR_BLOCK)
    yield
    _keep_across_creases(kept, start, result, rows[3], facing, area, corners_of)
    yield
    if outline is not None and outline.vertices.size:  # what an outline vertex takes back: no pull-in
        result = outline.across(start, result, rows[:3, outline.vertices].T)
        facing = None  # its faces turned with it: the fold check reads them again
    normals = rows[:3]
    del rows, area
    yield from unfold_steps(kept, start, result, corners_of, facing)
    kept[still] = result[still]
    return kept, normals


def _projected(start, result, normals, kept, still, low, high):
    """Vertices low:high: ``kept`` the start plus the move along the (3, n) unit ``normals``, or the result
    where there is no normal (in no triangle: no surface to keep to); ``still`` where the vertex did not
    move."""
    begin = np.asarray(start[low:high], dtype=np.float64)
    move = result[low:high] - begin
    normal = normals[:3, low:high].T
    np.add(begin, normal * np.einsum("ij,ij->i", move, normal)[:, None], out=kept[low:high], casting="same_kind")
    still[low:high] = ~move.any(axis=1)
    bare = ~normal.any(axis=1)
    kept[low:high][bare] = result[low:high][bare]


@dataclass(frozen=True)
class Outline:
    """Open borders smoothed as curves: ``vertices``, those on exactly two border edges (sorted), with
    their two neighbours along the border (``before``, ``after``), the direction into the surface at each
    (``inward``: towards the mean of its neighbours) and the curve each lies on (``loop``: a label per
    vertex); ``border``, every border vertex (sorted), and ``curve``, their (k, 3) positions after the 1-D
    smoothing."""

    vertices: np.ndarray
    before: np.ndarray
    after: np.ndarray
    inward: np.ndarray
    loop: np.ndarray
    border: np.ndarray
    curve: np.ndarray

    def curve_at(self, vertices):
        return self.curve[np.searchsorted(self.border, vertices)]

    def across(self, start, result, normals):
        """``result`` (as float64) with each outline vertex at its start plus its move in ``result`` along
        its normal (``normals``: (k, 3), one per outline vertex) plus its curve move across the curve within
        the surface (along n x t, t the curve's direction there), less that move's median over its curve,
        and at most as long as the vertex's whole move in ``result``: the slide an outline vertex takes back
        where keeping folds the layout. Smoothing a curve shrinks it (a hole most); noise moves it across by
        nothing in the middle, so a curve keeps its place and its size (the median: the few corners a
        smoothing rounds off do not move the rest). On a ragged outline (a range scan's cut, a coarse scan's
        rim) the curve smoothing rounds the jags off by more than an edge where the smoother moved the
        vertex by the noise: the bound keeps that shape."""
        v, n = self.vertices, normals
        side = np.cross(n, self.curve_at(self.after) - self.curve_at(self.before))
        side *= np.where(np.einsum("ij,ij->i", side, self.inward) < 0, -1.0, 1.0)[:, None]  # into the surface
        length = np.sqrt(np.einsum("ij,ij->i", side, side))
        side /= np.where(length > 0, length, 1.0)[:, None]
        origin = start[v].astype(np.float64)
        inwards = np.einsum("ij,ij->i", self.curve_at(v) - origin, side)
        inwards -= _group_medians(inwards, self.loop)[self.loop]
        move = result[v] - origin
        reach = np.sqrt(np.einsum("ij,ij->i", move, move))
        np.clip(inwards, -reach, reach, out=inwards)
        target = result.astype(np.float64)
        target[v] = origin + _along(move, n) + inwards[:, None] * side
        return target


def outline_curves(border_edges, n_vertices):
    """(vertices, before, after): the vertices on exactly two of the (m, 2) ``border_edges``, sorted, with
    their two neighbours along the border (a vertex where more or fewer border edges meet ends a curve).
    ``curve_labels`` and ``inward_directions`` give an Outline the rest."""
    on_curve = np.bincount(np.ravel(border_edges), minlength=n_vertices) == 2
    heads = np.concatenate((border_edges[:, 0], border_edges[:, 1]))
    tails = np.concatenate((border_edges[:, 1], border_edges[:, 0]))
    order = np.argsort(heads, kind="stable")
    heads, tails = heads[order], tails[order]
    vertices = np.flatnonzero(on_curve)
    first = np.searchsorted(heads, vertices)
    return vertices, tails[first], tails[first + 1]


def curve_labels(border_edges, vertices):
    """(k,) the curve each of the outline ``vertices`` lies on: the components of the border edges between
    them (a vertex where more or fewer than two border edges meet cuts a curve)."""
    on = np.isin(border_edges, vertices).all(axis=1)
    local = np.searchsorted(vertices, border_edges[on])
    graph = sp.coo_matrix((np.ones(len(local)), (local[:, 0], local[:, 1])), shape=(vertices.size,) * 2)
    return connected_components(graph, directed=False)[1]


def inward_directions(positions, operator, vertices):
    """(k, 3): from each of ``vertices`` to the mean of its neighbours (core.adjacency.Umbrella) in
    ``positions``: into the surface, at a border vertex."""
    owner, neighbour = neighbours(vertices, operator)
    points = np.asarray(positions, dtype=np.float64)
    mean = np.stack([np.bincount(owner, weights=points[neighbour, k], minlength=vertices.size) for k in range(3)], 1)
    return mean / np.maximum(operator.degree[vertices], 1)[:, None] - points[vertices]


def _group_medians(values, labels):
    """The median of ``values`` per label 0..max (the upper middle of an even count)."""
    order = np.lexsort((values, labels))
    counts = np.bincount(labels)
    return values[order][np.cumsum(counts) - counts + counts // 2]


def _keep_across_creases(kept, start, result, agreement, faces, area, corners_of):
    """Set ``kept`` at the crease and corner vertices of the result (see CREASE), whose unit face normals
    ``faces`` (3, t) and twice-areas ``area`` are given: the start plus the move less its part along the
    crease (the normal tensor's smallest axis); a corner's whole move. ``agreement``: core.geometry's
    vertex_normals' (how far each vertex's faces face one way)."""
    n = len(kept)
    # The middle eigenvalue is at most 1 less the tensor's share along the vertex normal n, which is at least
    # (sum_f area_f n_f . n)^2 / (sum_f area_f)^2 = agreement^2 (Cauchy-Schwarz): only a vertex whose
    # agreement^2 is at most 1 - CREASE can reach CREASE (a little slack: the faces' own rounding).
    candidates = np.flatnonzero(agreement * agreement <= (1.0 - CREASE) + 1e-6)
    if candidates.size == 0:
        return
    chosen = np.zeros(n, dtype=bool)
    chosen[candidates] = True
    place = np.empty(n, dtype=index_dtype(n))  # read at the candidates only
    place[candidates] = np.arange(candidates.size)
    entries = np.zeros((7, candidates.size))  # the tensor's xx, yy, zz, xy, xz, yz, then the faces' area
    for column in corners_of:
        mine = np.flatnonzero(chosen[column])
        owner, unit, weight = place[column[mine]], faces[:, mine].astype(np.float64), area[mine].astype(np.float64)
        for k, (a, b) in enumerate(SYMMETRIC_ENTRIES):
            entries[k] += np.bincount(owner, weight * unit[a] * unit[b], candidates.size)
        entries[6] += np.bincount(owner, weight, candidates.size)
    entries[:6] /= np.where(entries[6] > 0.0, entries[6], 1.0)  # no face with area: no crease
    low, middle, _ = symmetric_eigenvalues(*entries[:6])
    crease = middle >= CREASE
    rows = candidates[crease]
    moves = np.subtract(result[rows], start[rows], dtype=np.float64)
    line = low[crease] < CORNER  # a corner keeps its whole move; a crease gives up its part along the crease
    moves[line] -= _along(moves[line], smallest_eigenvectors(*entries[:6, crease][:, line]))
    kept[rows] = start[rows] + moves


def _along(move, direction):
    """Each row of ``move``'s component along the unit rows of ``direction``."""
    return np.einsum("ij,ij->i", move, direction)[:, None] * direction


def unfold_steps(kept, start, result, corners_of, facing=None):
    """Where ``kept`` folds or flattens a triangle, its corners take back part of the slide to ``result``,
    in place. Shadows are read along the smoothed triangle's normal: a kept triangle is folded where its
    shadow is not positive, flattened where it is under FOLDED times the input's shadow or FLAT times the
    input's area.

    Where at most _HALVED of the triangles fold at first, the corners of a folded triangle take back half
    of what is left of the slide for each of the first _ROUNDS rounds it stays folded, then all of it; where
    more do, all of it at once; where more than _FOLDED_LAYOUT do (noise folded the layout nearly
    everywhere), every vertex does. Rounds go on until no triangle with a corner off the result is folded,
    _LAST at most (the corners of those still folded then take all of it), each reading only the triangles
    at the corners just moved. Shadows in single precision, blocks of triangles on threads. ``corners_of``:
    the triangles' three corner columns; ``facing``: the result's unit face normals (``_unit_faces``), if
    the caller has them. Single-precision coordinates are taken about a vertex of ``start`` (``_origin``).
    A generator: yields (None) after the first check and after each round."""
    t = len(corners_of[0])
    origin = _origin(start)
    if facing is None:
        facing = _unit_faces(_planar(result, origin), corners_of)[0]
    least = np.empty(t, dtype=np.float32)
    planar, before = _planar(kept, origin), _planar(start, origin)
    folded = np.concatenate(
        parallel.run_chunks(
            lambda low, high: _first_check(planar, before, corners_of, facing, least, low, high), t, _BLOCK
        )
    )
    yield
    share = away = checked = None
    for round_ in range(1, _LAST + 1):
        if share is not None:  # a triangle all of whose corners are back at the result stays as it is
            picked = [column[checked] for column in corners_of]
            folded = _folded(planar, picked, facing[:, checked], least[checked])
            folded &= (share[picked[0]] > 0) | (share[picked[1]] > 0) | (share[picked[2]] > 0)
            folded = checked[folded]
        else:
            folded = np.flatnonzero(folded)
            halving = folded.size <= _HALVED * t
            if folded.size > _FOLDED_LAYOUT * t:  # noise folded the layout nearly everywhere: nothing to keep
                kept[:] = result
                return
        if folded.size == 0:
            return
        moved = np.zeros(len(kept), dtype=bool)
        for column in corners_of:
            moved[column[folded]] = True
        corners = np.flatnonzero(moved)
        if share is None:
            share, away = np.ones(len(kept), dtype=np.float32), kept - result
        share[corners] = 0.5 * share[corners] if halving and round_ <= _ROUNDS and round_ < _LAST else 0.0
        kept[corners] = result[corners] + share[corners, None] * away[corners]
        planar[:, corners] = (kept[corners] - origin).T
        checked = np.flatnonzero(moved[corners_of[0]] | moved[corners_of[1]] | moved[corners_of[2]])
        yield


def _first_check(planar, before, corners_of, facing, least, low, high):
    """Triangles low:high: their least shadows into ``least``, and whether the kept ``planar`` one is folded
    against the smoothed unit normals ``facing`` (returned)."""
    picked = [column[low:high] for column in corners_of]
    normal = facing[:, low:high]
    area = _cross(before, picked)
    bound = np.maximum(FOLDED * dot(area, normal), FLAT * np.sqrt(dot(area, area)))
    bound[~normal.any(axis=0)] = -np.inf  # a smoothed triangle without area has no side to fold to
    least[low:high] = bound
    return _folded(planar, picked, normal, bound)


def _unit_faces(planar, corners_of):
    """((3, t) unit normals, (t,) twice-areas) of the triangles over (3, n) ``planar`` coordinates, (0, 0, 0)
    for one without area; blocks of triangles on threads."""
    t = len(corners_of[0])
    facing, area = np.empty((3, t), dtype=planar.dtype), np.empty(t, dtype=planar.dtype)

    def block(low, high):
        normal = _cross(planar, [column[low:high] for column in corners_of])
        length = np.sqrt(dot(normal, normal))
        normal /= np.where(length > 0, length, 1.0)
        facing[:, low:high], area[low:high] = normal, length

    parallel.run_chunks(block, t, _BLOCK)
    return facing, area


def _folded(planar, picked, facing, least):
    """Whether the triangles of corner arrays ``picked`` over ``planar`` fold against ``facing``/``least``."""
    shadow = dot(_cross(planar, picked), facing)
    return (shadow <= 0.0) & (least > -np.inf) | (shadow < least)


def _origin(points):
    """A point of the mesh, its first vertex (zeros for none): single-precision coordinates taken from it
    keep the mesh's size in digits wherever it lies (a georeferenced scan sits millions of units out)."""
    return np.array(points[0], dtype=np.float64) if len(points) else np.zeros(3)


def _planar(points, origin):
    """(3, n) single-precision coordinate rows of (n, 3) ``points`` less ``origin``."""
    out = np.empty((3, len(points)), dtype=np.float32)
    points, origin = np.asarray(points), np.asarray(origin, dtype=np.float64)[:, None]

    def block(low, high):
        np.subtract(points[low:high].T, origin, out=out[:, low:high], casting="same_kind")

    parallel.run_chunks(block, len(points), VECTOR_BLOCK)
    return out


def _cross(planar, corners_of):
    """(3, t) twice-area normals of the triangles whose corners are the index arrays ``corners_of``
    (a, b, c), over (3, n) ``planar`` coordinates, coordinate by coordinate."""
    a, b, c = corners_of
    return cross([row.take(b) - row.take(a) for row in planar], [row.take(c) - row.take(a) for row in planar])
