"""Exact Euclidean minimum spanning tree (EMST) of a point set, in O(n log n) practice.

Why not just "k-nearest-neighbour graph + csgraph.minimum_spanning_tree": that is the MST of the kNN
graph, which equals the EMST only when the kNN graph contains every EMST edge. It does not for scan
lines or separated clusters (no kNN edge crosses the gap), nor near density jumps (a point can be
among nobody's k nearest). And csgraph drops zero-length edges between duplicate points.

What we do instead is Borůvka's algorithm on the complete graph, with the kNN lists as a cache:

* Duplicates are merged first: the tree spans the distinct points (an extra copy joins it by a
  zero-length edge to its representative; such edges are in every EMST).
* Each round, every component C needs its shortest edge to another component (cut property: that
  edge is in an EMST). The kNN edges crossing components give a candidate of length best(C). The
  candidate is provably the shortest outgoing edge unless some point p of C has all k of its nearest
  neighbours inside C ("exhausted") and d_k(p) < best(C): a non-kNN edge from p is at least d_k(p)
  long, and a point with a foreign point in its list already offered its shortest outgoing edge.
  So C is *certified* when best(C) <= min d_k(p) over its exhausted points.
* When too few components are certified, the others get their exact shortest outgoing edge from
  KD-tree queries restricted to other components. Few askers: growing-k queries on the full tree
  until a foreign point turns up or the list passes the bound. Many askers (scan lines): components
  get distinct non-zero codes, and for each bit of the code a tree over the points whose bit is 0
  answers the queries of points whose bit is 1 and vice versa. Two different codes differ in some
  bit, so the minimum over bits is the nearest point of another component. A sample of the askers
  goes first to bound each component, so the rest search small balls. Only exhausted points below
  their component's bound ask.
* Exact answers are remembered across rounds: a point's nearest foreign point stays so while it is
  foreign (foreign points only get fewer), and is offered like a kNN edge; once it has merged into
  the point's component, its distance (like the bound of an empty search) is a floor below which
  no foreign point of that point can lie, which certifies components and shrinks searches.
* Ties: each component takes *a* shortest outgoing edge. With ties the picks can close a cycle, and
  every such cycle consists of equally long edges (around it each pick is no longer than the
  previous one), so keeping a spanning forest of the picks (dropping one edge per cycle) keeps the
  result a minimum spanning tree.
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from ..adjacency import pairs_in_order
from ..slices import to_end
from .stepwise import Slices


def merge_duplicates(points):
    """Return (first, representative): ``first`` are the indices of the distinct points (the first
    copy of each, increasing); ``representative[i]`` is the position in ``first`` of the copy of i."""
    n = points.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    order = np.lexsort((np.arange(n), points[:, 2], points[:, 1], points[:, 0]))
    ordered = points[order]
    new_group = np.ones(n, dtype=bool)
    new_group[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    group = np.cumsum(new_group) - 1
    group_first = order[new_group]  # the lowest index of each group (ties sorted by index)
    rank = np.argsort(group_first, kind="stable")  # renumber groups by their first index
    position = np.empty_like(rank)
    position[rank] = np.arange(rank.size)
    representative = np.empty(n, dtype=np.int64)
    representative[order] = position[group]
    return group_first[rank], representative


class NeighbourIndex:
    """Distinct points in KD-tree order, their KD-tree and their k nearest neighbours. (KD-tree
    order puts neighbouring points close in memory, which makes the kNN query and every later
    gather of neighbours much faster.)

    ``points[j]`` is input point ``original[j]``; ``representative`` maps every input point to its
    row here. ``distance``/``neighbour`` (m, k) hold the k nearest other points, nearest first.
    """

    def __init__(self, points, k, scale=1.0):
        to_end(self.build(points, k, scale))

    @classmethod
    def in_steps(cls, points, k, scale=1.0):
        """The index built stepwise (core.pointcloud.stepwise): yields between blocks of the kNN query."""
        index = cls.__new__(cls)
        yield from index.build(points, k, scale)
        return index

    def build(self, points, k, scale):
        # ``points / scale`` (scale a power of two, see validation.power_of_two_scale): exact, and
        # duplicates are merged after the division, so the rows stay distinct even where it underflows.
        if scale != 1.0 or points.dtype != np.float64:
            points = np.divide(points, scale, dtype=np.float64)
        first, representative = merge_duplicates(points)
        order = cKDTree(points[first]).indices if first.size else np.zeros(0, dtype=np.intp)
        self.original = first[order]
        row = np.empty_like(order)
        row[order] = np.arange(order.size)
        self.representative = row[representative]
        self.points = np.ascontiguousarray(points[self.original])
        del points  # (the divided copy) before the kNN query's peak
        self.tree = cKDTree(self.points)
        m = self.points.shape[0]
        self.k = int(min(k, max(m - 1, 0)))
        self.distance = np.zeros((m, self.k))
        self.neighbour = np.zeros((m, self.k), dtype=np.int64)
        if self.k == 0:
            return
        slices = Slices()
        step = max(1, _QUERY_ENTRIES // (self.k + 1))  # in blocks: small result arrays, reused
        for start in range(0, m, step):
            rows = slice(start, min(start + step, m))
            distance, neighbour = self.tree.query(self.points[rows], self.k + 1, workers=-1)
            # Points are distinct, so each point is its own unique nearest (distance 0): column 0.
            self.distance[rows] = distance[:, 1:]
            self.neighbour[rows] = neighbour[:, 1:]
            if slices.due(distance.size) and rows.stop < m:
                yield rows.stop / m

    @property
    def n_points(self):
        return self.points.shape[0]


def _spanning_forest(u, v, n_components):
    """Indices of a spanning forest of the multigraph on components with edges (u[i], v[i])."""
    key = np.minimum(u, v) * n_components + np.maximum(u, v)
    _, unique = np.unique(key, return_index=True)
    weights = np.arange(1, unique.size + 1, dtype=np.float64)  # distinct and > 0: csgraph keeps them
    graph = sp.coo_matrix((weights, (u[unique], v[unique])), shape=(n_components,) * 2).tocsr()
    forest = minimum_spanning_tree(graph).tocoo()
    return unique[forest.data.astype(np.int64) - 1]


_QUERY_ENTRIES = 1 << 22  # neighbours per KD-tree query call: bounds the (rows, k) result arrays


def _nearest_foreign_by_growing_k(tree, label_code, ask, bound, k, budget):
    """Query the full tree with growing k until each asker either meets a point of another code
    (the first one met is its nearest foreign point) or has seen every point closer than its bound.
    Stops when the next k would exceed ``budget`` neighbours in all. Returns (distance, index,
    resolved)."""
    distance_out = np.full(ask.size, np.inf)
    index_out = np.full(ask.size, -1, dtype=np.int64)
    resolved = np.zeros(ask.size, dtype=bool)
    m = tree.n
    todo = np.arange(ask.size)
    while todo.size and k * todo.size <= budget:
        k = min(k, m)
        step = max(1, _QUERY_ENTRIES // k)
        done_rows = []
        for start in range(0, todo.size, step):
            rows = todo[start : start + step]
            limit = bound[rows]
            upper = float(limit.max())
            distance, found = tree.query(
                tree.data[ask[rows]], k, workers=-1, distance_upper_bound=upper if np.isfinite(upper) else np.inf
            )
            distance, found = distance.reshape(rows.size, k), found.reshape(rows.size, k)
            valid = np.isfinite(distance)
            foreign = valid & (label_code[np.where(valid, found, 0)] != label_code[ask[rows]][:, None])
            foreign &= distance < limit[:, None]
            has = foreign.any(axis=1)
            first = np.argmax(foreign, axis=1)
            distance_out[rows[has]] = distance[has, first[has]]
            index_out[rows[has]] = found[has, first[has]]
            # Done without a hit when the list ran past the bound (or past every point within reach).
            done_rows.append(rows[has | ~valid[:, -1] | (distance[:, -1] >= limit) | (k >= m)])
        done = np.concatenate(done_rows)
        resolved[done] = True
        todo = todo[~resolved[todo]]
        k *= 2
    return distance_out, index_out, resolved


_SAMPLE_STRIDE = 16


def _exact_nearest_foreign(tree_points, label_code, ask, bound, tree=None, k=16, return_bound=False):
    """For each point index in ``ask``: the nearest point whose code differs, if closer than
    ``bound`` (per asking point). Returns (distance, index), inf / -1 where none is closer; with
    ``return_bound`` also the bound each asker was finally searched below (no point of another
    code is nearer than that where none was found).

    Callers only use the minimum per code, so a point may also report nothing when another point of
    its code already found something at least as near. Few askers (k x askers <= points) grow k on
    the full tree; otherwise three stages:
    1. many askers (e.g. whole scan lines, whose kNN lists never leave the line): a sample of every
       16th asker (spread out: rows are in KD-tree order) searches first and bounds each code;
    2. growing-k queries on the full tree (when given), which settle most askers below that bound;
    3. the rest: one KD-tree per code bit (_query_by_bits), searching only below the bound."""
    best_distance = np.full(ask.size, np.inf)
    best_index = np.full(ask.size, -1, dtype=np.int64)
    bound = np.asarray(bound, dtype=np.float64).copy()
    if ask.size == 0:
        return (best_distance, best_index, bound) if return_bound else (best_distance, best_index)
    rest = np.arange(ask.size)
    if tree is not None and k * ask.size <= tree_points.shape[0]:
        # Few askers (the usual case on surfaces): growing-k queries on the one tree we have cost
        # far less than building two trees per code bit over all points.
        found_distance, found_index, resolved = _nearest_foreign_by_growing_k(
            tree, label_code, ask, bound, k, budget=tree_points.shape[0]
        )
        best_distance[resolved], best_index[resolved] = found_distance[resolved], found_index[resolved]
        rest = rest[~resolved]
        tree = None  # whoever is left needs the bit search
    if rest.size > 4 * _SAMPLE_STRIDE:
        sample = rest[::_SAMPLE_STRIDE]
        best_distance[sample], best_index[sample] = _query_by_bits(tree_points, label_code, ask[sample], bound[sample])
        # No point of another code is nearer to a sample point than this (exact below its bound).
        sample_floor = np.minimum(best_distance[sample], bound[sample])
        code_bound = np.full(int(label_code.max()) + 1, np.inf)
        np.minimum.at(code_bound, label_code[ask[sample]], best_distance[sample])
        bound = np.minimum(bound, code_bound[label_code[ask]])
        searched = np.zeros(rest.size, dtype=bool)
        searched[::_SAMPLE_STRIDE] = True
        rest = rest[~searched & ~_ruled_out(tree_points, label_code, ask, rest, sample_floor, bound)]
    if tree is not None and 0 < rest.size < _FEW_ASKERS:
        # A pilot (every 16th) shows whether growing k pays: on scan lines far apart relative to
        # their point spacing it would need hundreds of neighbours per point.
        pilot = np.zeros(rest.size, dtype=bool)
        pilot[::_SAMPLE_STRIDE] = True
        left = np.ones(rest.size, dtype=bool)  # still to search by bits
        for part in (pilot, ~pilot):
            position = np.flatnonzero(part)
            if position.size == 0:
                continue
            rows = rest[position]
            found_distance, found_index, resolved = _nearest_foreign_by_growing_k(
                tree, label_code, ask[rows], bound[rows], k, budget=4 * k * rows.size
            )  # k <= 4 k0
            best_distance[rows[resolved]] = found_distance[resolved]
            best_index[rows[resolved]] = found_index[resolved]
            left[position[resolved]] = False
            if part is pilot and position.size >= 8 and resolved.mean() < 0.5:
                break  # the others go straight to the bit search
        rest = rest[left]
    if rest.size:
        best_distance[rest], best_index[rest] = _query_by_bits(tree_points, label_code, ask[rest], bound[rest])
    return (best_distance, best_index, bound) if return_bound else (best_distance, best_index)


def _ruled_out(tree_points, label_code, ask, rows, sample_floor, bound):
    """Mask over ``rows`` (positions in ``ask``; the sample was ``rows[::_SAMPLE_STRIDE]``, with
    ``sample_floor`` its lower bounds on the distance to another code): the askers that cannot have
    a point of another code nearer than their ``bound``. By the triangle inequality, an asker p of
    the same code as a sample point s is at least floor(s) - |p - s| from every other code; the two
    sample points around p in KD-tree order are usually near it. On separated clusters this rules
    out most points (those not facing the nearest cluster); on evenly spaced scan lines, few."""
    position = np.arange(rows.size)
    points = tree_points[ask[rows]]
    code = label_code[ask[rows]]
    lower = np.full(rows.size, -np.inf)
    last = (rows.size - 1) // _SAMPLE_STRIDE
    for near in (position // _SAMPLE_STRIDE, np.minimum(position // _SAMPLE_STRIDE + 1, last)):
        s = rows[near * _SAMPLE_STRIDE]
        gap = np.sqrt(np.einsum("ij,ij->i", points - tree_points[ask[s]], points - tree_points[ask[s]]))
        # A hair of slack, so that rounding can never rule out a point that ties the bound.
        candidate = sample_floor[near] * (1.0 - 1e-12) - gap * (1.0 + 1e-12)
        lower = np.where(code == label_code[ask[s]], np.maximum(lower, candidate), lower)
    return lower >= bound[rows]


def _query_by_bits(tree_points, label_code, ask, bound):
    """Exact nearest point of another code below ``bound``: codes differ in some bit, so one tree
    per bit and side (points whose bit is 0 answer points whose bit is 1 and vice versa) covers all.
    Askers are queried in groups of similar bound, because a KD-tree query takes one upper bound."""
    best_distance = np.full(ask.size, np.inf)
    best_index = np.full(ask.size, -1, dtype=np.int64)
    if ask.size == 0:
        return best_distance, best_index
    n_bits = int(label_code.max()).bit_length()
    for bit in range(n_bits):
        side = (label_code >> bit) & 1
        for target_side in (0, 1):
            targets = np.flatnonzero(side == target_side)
            askers = np.flatnonzero(side[ask] != target_side)
            if targets.size == 0 or askers.size == 0:
                continue
            tree = cKDTree(tree_points[targets])
            # Only a point nearer than the best found so far (by earlier bits) can matter: once the
            # first tree has answered, every later search is a small ball, not an unbounded one.
            current = np.minimum(bound[askers], best_distance[askers])
            with np.errstate(divide="ignore"):
                group = np.where(np.isfinite(current), np.floor(np.log2(np.maximum(current, 1e-300))), np.inf)
            for value in np.unique(group):
                in_group = group == value
                rows, limit = askers[in_group], current[in_group]
                upper = float(limit.max())
                distance, found = tree.query(
                    tree_points[ask[rows]], 1, workers=-1, distance_upper_bound=upper if np.isfinite(upper) else np.inf
                )
                better = (distance < limit) & (distance < best_distance[rows])
                best_distance[rows[better]] = distance[better]
                best_index[rows[better]] = targets[found[better]]
    return best_distance, best_index


# Below this many askers left after the sample, growing-k queries on the full tree may beat the bit
# search (a pilot decides). Every search is a single bounded query: once each search after the first
# is bounded by the best point found so far, a dual-tree traversal per group of askers is slower
# (bench/results/2026-11-23-point-clouds.md at commit 555017f, "Exact EMST of scan lines").
_FEW_ASKERS = 2048


def _per_component_pick(n_components, label_u, label_v, weight, u, v, best=None):
    """For every component, one shortest edge among (u, v, weight) that touches it (inf, -1 if none).
    ``best``: the shortest length per component, when the caller knows it."""
    if best is None:
        best = np.full(n_components, np.inf)
        np.minimum.at(best, label_u, weight)
        np.minimum.at(best, label_v, weight)
    pick_u = np.full(n_components, -1, dtype=np.int64)
    pick_v = np.full(n_components, -1, dtype=np.int64)
    for label in (label_u, label_v):
        hit = weight == best[label]
        # Any of several equally short edges will do (see the module docstring on ties).
        pick_u[label[hit]] = u[hit]
        pick_v[label[hit]] = v[hit]
    return best, pick_u, pick_v


# Exact queries run once more than this fraction of the components are not certified by their kNN
# lists; until then the certified ones merge first (any value keeps the tree exact, it trades speed).
_UNCERTAIN_FRACTION = 0.5


def boruvka_emst(index):
    """EMST edges (rows of ``index.points``) and their lengths, exactly."""
    return to_end(emst_steps(index))


class _ForeignCache:
    """Exact searches, remembered: a point's nearest foreign point stays its nearest foreign point
    while it is foreign (the foreign points only get fewer), and once it has joined the point's
    component, every foreign point is at least as far as it was (``floor``, like an empty search
    below a bound)."""

    def __init__(self, m):
        self.distance = np.full(m, np.inf)
        self.index = np.full(m, -1, dtype=np.int64)
        self.floor = np.zeros(m)

    def still_foreign(self, label):
        """Retire the entries whose point has merged (their distance becomes a floor); the rest."""
        cached = np.flatnonzero(self.index >= 0)
        merged_in = cached[label[self.index[cached]] == label[cached]]
        self.floor[merged_in] = np.maximum(self.floor[merged_in], self.distance[merged_in])
        self.index[merged_in] = -1
        return np.flatnonzero(self.index >= 0)

    def record(self, ask, found_distance, found, searched):
        hit = found >= 0
        self.distance[ask[hit]], self.index[ask[hit]] = found_distance[hit], found[hit]
        self.floor[ask[~hit]] = np.maximum(self.floor[ask[~hit]], searched[~hit])


class _CrossingEdges:
    """The kNN edges that cross between components, in the order of the lists (by source point,
    each point's edges nearest first), and the same edges grouped by target point (``by_dst``,
    positions in the lists): each component's shortest crossing edge is then the shortest over its
    points' first edge out and shortest edge in, without a scatter over all edges."""

    def __init__(self, index):
        m, k = index.n_points, index.k
        self.src = np.repeat(np.arange(m, dtype=np.int64), k)
        self.dst = index.neighbour.ravel()
        self.weight = index.distance.ravel()
        self.by_dst = _grouped_by_target(self.src, self.dst, m)

    def keep(self, crossing):
        """Keep the edges where ``crossing`` (a mask over them) holds."""
        kept = crossing[self.by_dst]
        position = np.cumsum(crossing, dtype=np.int64)
        position -= 1
        self.by_dst = position[self.by_dst[kept]]
        self.src, self.dst, self.weight = self.src[crossing], self.dst[crossing], self.weight[crossing]

    def shortest(self, label, n_components):
        """Per component the length of its shortest crossing edge (inf if none)."""
        m = label.size
        if not self.src.size:
            return np.full(n_components, np.inf)
        per_point = np.full(m, np.inf)
        first_out = np.flatnonzero(np.concatenate(([True], self.src[1:] != self.src[:-1])))
        per_point[self.src[first_out]] = self.weight[first_out]  # each list is sorted, nearest first
        target = self.dst[self.by_dst]
        first_in = np.flatnonzero(np.concatenate(([True], target[1:] != target[:-1])))
        shortest_in = np.minimum.reduceat(self.weight[self.by_dst], first_in)
        per_point[target[first_in]] = np.minimum(per_point[target[first_in]], shortest_in)
        return _group_min(label, per_point, n_components)


def _group_min(group, values, n_groups):
    """Per group (0 <= group < n_groups) the smallest of its ``values`` (inf if none): a counting
    sort by group and one reduction (np.minimum.at scatters element by element, far slower)."""
    best = np.full(n_groups, np.inf)
    placed = None
    if n_groups < 2**31 and group.size < 2**31:
        placed = pairs_in_order(group.astype(np.int32), np.zeros(group.size, np.int32), n_groups, values)
    if placed is None:
        np.minimum.at(best, group, values)
        return best
    indptr, _, ordered = placed
    filled = indptr[:-1] < indptr[1:]
    best[filled] = np.minimum.reduceat(ordered, indptr[:-1][filled])
    return best


def _grouped_by_target(src, dst, m):
    """Positions of the edges (src, dst) grouped by dst, each group in position order."""
    if m < 2**31:
        placed = pairs_in_order(dst.astype(np.int32), src.astype(np.int32), m, np.arange(src.size, dtype=np.int64))
        if placed is not None:
            return placed[2]  # by dst, then src: position order, as the edges are listed by src
    return np.argsort(dst, kind="stable")


def _knn_picks(n_components, label, edges, cache):
    """Per component the shortest of its crossing kNN edges and remembered exact answers."""
    src, dst, weight = edges.src, edges.dst, edges.weight
    label_src, label_dst = label[src], label[dst]
    best = edges.shortest(label, n_components)
    cached = cache.still_foreign(label)  # still foreign: still the exact nearest
    if not cached.size:
        return _per_component_pick(n_components, label_src, label_dst, weight, src, dst, best)
    np.minimum.at(best, label[cached], cache.distance[cached])
    np.minimum.at(best, label[cache.index[cached]], cache.distance[cached])
    return _per_component_pick(
        n_components,
        np.concatenate([label_src, label[cached]]),
        np.concatenate([label_dst, label[cache.index[cached]]]),
        np.concatenate([weight, cache.distance[cached]]),
        np.concatenate([src, cached]),
        np.concatenate([dst, cache.index[cached]]),
        best,
    )


def _exact_picks(index, label, n_components, inside, reach, uncertain, picks, cache):
    """Improve the picks of the ``uncertain`` components by exact searches of their exhausted points
    below the best edge known (``picks``: best, pick_u, pick_v, updated in place)."""
    best, pick_u, pick_v = picks
    ask = inside[uncertain[label[inside]] & (reach < best[label[inside]])]
    code = np.zeros(n_components, dtype=np.int64)
    code[uncertain] = np.arange(1, int(uncertain.sum()) + 1)
    found_distance, found, searched = _exact_nearest_foreign(
        index.points, code[label], ask, best[label[ask]], tree=index.tree, k=2 * max(index.k, 1), return_bound=True
    )
    cache.record(ask, found_distance, found, searched)
    hit = found >= 0
    exact_best, exact_u, exact_v = _per_component_pick(
        n_components, label[ask[hit]], label[ask[hit]], found_distance[hit], ask[hit], found[hit]
    )
    improve = exact_best < best
    best[improve] = exact_best[improve]
    pick_u[improve], pick_v[improve] = exact_u[improve], exact_v[improve]


def emst_steps(index):
    """boruvka_emst stepwise (core.pointcloud.stepwise): yields between Borůvka rounds, the fraction
    of the merging done (on a log scale of the components left); returns (edges, lengths)."""
    m = index.n_points
    points = index.points
    label = np.arange(m, dtype=np.int64)
    n_components = m
    if m <= 1:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    radius = index.distance[:, -1]  # d_k(p): every point outside p's list is at least this far
    edges = _CrossingEdges(index)
    exhausted = np.zeros(m, dtype=bool)
    cache = _ForeignCache(m)
    tree_u, tree_v = [], []
    slices = Slices()
    while n_components > 1:
        if n_components < m:  # (at first every point is its own component: each kNN pair crosses)
            crossing = label[edges.src] != label[edges.dst]
            # A point none of whose neighbours is foreign stays so: components only grow.
            offers = np.zeros(m, dtype=bool)
            offers[edges.src[crossing]] = True
            exhausted |= ~offers
            edges.keep(crossing)
        picks = _knn_picks(n_components, label, edges, cache)
        best = picks[0]
        inside = np.flatnonzero(exhausted & (cache.index < 0))  # exhausted, nearest foreign unknown
        reach = np.maximum(radius[inside], cache.floor[inside])  # no foreign point is nearer
        lower = _group_min(label[inside], reach, n_components)
        uncertain = lower < best
        if uncertain.sum() > _UNCERTAIN_FRACTION * n_components or uncertain.all():
            _exact_picks(index, label, n_components, inside, reach, uncertain, picks, cache)
            chosen = np.isfinite(best)  # now exact for every component
        else:
            chosen = ~uncertain & np.isfinite(best)
        u, v = picks[1][chosen], picks[2][chosen]
        keep = _spanning_forest(label[u], label[v], n_components)
        tree_u.append(u[keep])
        tree_v.append(v[keep])
        merged = sp.coo_matrix((np.ones(keep.size), (label[u[keep]], label[v[keep]])), shape=(n_components,) * 2)
        n_components, relabel = connected_components(merged, directed=False)
        label = relabel[label].astype(np.int64)
        if slices.due(edges.src.size) and n_components > 1:
            yield 1.0 - np.log(n_components) / np.log(m)
    u, v = np.concatenate(tree_u), np.concatenate(tree_v)
    return np.stack([u, v], axis=1), np.sqrt(np.einsum("ij,ij->i", points[u] - points[v], points[u] - points[v]))
