"""Surface description graph (SDG): the EMST plus adaptive nearest-neighbour edges (paper section 7).

Mencl & Müller's SDG rules are not published in enough detail to reproduce, so this is our rule.
It works on distinct points (``NeighbourIndex`` rows) and uses one number per point:

* **Local spacing h(p)**: the distance from p to its nearest neighbour that is *not* roughly on the
  line through p and its nearest neighbour (angle >= 30 degrees from it). That is the radius at
  which p's neighbourhood becomes two-dimensional, i.e. the sample spacing of the surface at p. On
  an even sampling it is about the nearest-neighbour distance; on scan lines (dense rows far apart)
  it is the distance to the next row, which is the spacing a surface neighbourhood must bridge.
  If all ``neighbours`` cached neighbours lie on that line, h(p) is the farthest of them.

* **EMST edges** (the SDG's kernel, which connects everything) are kept unless they are
  *inconsistent* in Zahn's sense: longer than ``gap_factor`` x max(h(p), h(q)). Such an edge jumps
  a gap much wider than the spacing on *both* sides, e.g. between separated clusters or from a
  surface to a far-off group of points, and smoothing across it would drag the two towards each
  other.

* **Adaptive nearest-neighbour edges**: p is joined to each cached neighbour q with
  |pq| <= ``spacing_factor`` x min(h(p), h(q)). The number of neighbours per point therefore follows
  the local density (median 6 on a clean even surface sampling with factor 2, 9 with 2.5, 12 with
  3; a little more on noisy samples; each point proposes at most ``neighbours``: wider
  neighbourhoods smooth noisy data better, see bench/results/2026-11-23-point-clouds.md at commit 555017f), and the
  min keeps a sparse point from reaching deep into a denser region.

The defaults of ``surface_description_graph`` (both factors 3) are the rule's own; smooth_point_cloud
passes its settings (spacing_factor 2.5, gap_factor 3) explicitly.

Guarantees (tested): every SDG edge is at most ``gap_factor`` x max(h(p), h(q)) long (we require
``spacing_factor <= gap_factor``); every EMST edge that satisfies this is present, so the SDG is
connected wherever the EMST has no inconsistent edge. (Two pieces of the EMST separated by a cut
edge can still be joined by an adaptive edge, but only one that is short for the spacing at both
of its own ends.)
"""

from dataclasses import dataclass

import numpy as np

from ..adjacency import pair_keys

# sin(30 degrees): how far off the nearest-neighbour line a neighbour must lie to make p's
# neighbourhood two-dimensional.
_OFF_LINE_SIN = 0.5
_CHUNK = 1 << 17  # rows per block: keeps the (rows, k, 3) temporaries to tens of MB


@dataclass(frozen=True)
class SurfaceGraph:
    edges: np.ndarray  # (m, 2) rows of the NeighbourIndex, each undirected edge once, low < high
    spacing: np.ndarray  # (n,) local spacing h(p)
    emst_kept: int  # EMST edges kept
    emst_cut: int  # EMST edges cut as gaps


def local_spacing(index):
    """h(p) for every row of ``index`` (see the module docstring); 0 for a lone point."""
    m, k = index.n_points, index.k
    if k == 0:
        return np.zeros(m)
    spacing = index.distance[:, -1].copy()
    if k == 1:
        return spacing
    points = index.points
    for start in range(0, m, _CHUNK):
        rows = slice(start, min(start + _CHUNK, m))
        # Component by component (r, k): the same sums as np.cross and a norm, without their overhead.
        neighbour = index.neighbour[rows]
        offset = [points[neighbour, j] - points[rows, j][:, None] for j in range(3)]  # nearest first
        line = [x[:, :1] / index.distance[rows, :1] for x in offset]
        a = [x[:, 1:] for x in offset]
        c = [a[1] * line[2] - a[2] * line[1], a[2] * line[0] - a[0] * line[2], a[0] * line[1] - a[1] * line[0]]
        cross = np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
        off_line = cross >= _OFF_LINE_SIN * index.distance[rows, 1:]
        found = off_line.any(axis=1)
        first = np.argmax(off_line, axis=1) + 1
        block = spacing[rows]
        block[found] = index.distance[rows][found, first[found]]
        spacing[rows] = block
    return spacing


def unique_sorted(keys):
    """Sorted distinct values (sort + mask: NumPy 2's np.unique hashes first, slower here)."""
    keys = np.sort(keys)
    return keys[np.concatenate(([True], keys[1:] != keys[:-1]))] if keys.size else keys


def reach_gap_problem(spacing_factor, gap_factor, names=("spacing_factor", "gap_factor")):
    """Why the SDG cannot join points with these factors, or None: an edge within reach (``spacing_factor``
    local spacings) must not count as a gap (longer than ``gap_factor`` spacings). ``names``: the two as the
    caller's user knows them (a panel's labels, the command line's options).

    Examples
    --------
    >>> import core
    >>> core.reach_gap_problem(2.0, 3.0) is None
    True
    >>> core.reach_gap_problem(3.0, 2.0)
    'spacing_factor (3) must not exceed gap_factor (2): a neighbour within reach would be cut off as a gap'
    """
    if spacing_factor <= gap_factor:
        return None
    reach, gap = names
    return (
        f"{reach} ({spacing_factor:g}) must not exceed {gap} ({gap_factor:g}): "
        "a neighbour within reach would be cut off as a gap"
    )


def surface_description_graph(index, emst_edges, *, spacing_factor=3.0, gap_factor=3.0):
    """The SDG of the distinct points of ``index`` given their EMST (rows of ``index``).

    Parameters
    ----------
    index : core.pointcloud.spanning_tree.NeighbourIndex
        The distinct points and their nearest neighbours.
    emst_edges : (n - 1, 2) int ndarray
        Their Euclidean minimum spanning tree, as rows of ``index``.
    spacing_factor, gap_factor : float, default 3.0
        The rule of the module docstring; 0 < spacing_factor <= gap_factor.

    Returns
    -------
    SurfaceGraph
        ``edges`` (each once, low < high), the local spacing h per point, EMST edges kept and cut.

    Raises
    ------
    ValueError
        ``spacing_factor`` not in (0, gap_factor].

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> index = NeighbourIndex(sphere, 16)  # distinct points, KD-tree, 16 nearest neighbours
    >>> tree, _ = boruvka_emst(index)  # the EMST's edges, as rows of index
    >>> graph = core.pointcloud.surface_description_graph(index, tree, spacing_factor=2.5)
    >>> graph.emst_kept, graph.emst_cut  # one closed surface: no gap to cut
    (499, 0)
    >>> bool(graph.edges.shape[0] > 4 * 500)  # about a dozen neighbours per point
    True
    """
    if not spacing_factor > 0:
        raise ValueError(f"spacing_factor must be above 0, got {spacing_factor}")
    problem = reach_gap_problem(spacing_factor, gap_factor)
    if problem:
        raise ValueError(problem)
    m = index.n_points
    spacing = local_spacing(index)
    u, v = emst_edges[:, 0], emst_edges[:, 1]
    length = np.linalg.norm(index.points[u] - index.points[v], axis=1)
    consistent = length <= gap_factor * np.maximum(spacing[u], spacing[v])

    n = max(m, 1)
    keys = [_edge_keys(u[consistent], v[consistent], n)]
    for start in range(0, m, _CHUNK):  # in blocks of rows: no full-size temporaries
        rows = slice(start, min(start + _CHUNK, m))
        neighbour = index.neighbour[rows]
        near = index.distance[rows] <= spacing_factor * np.minimum(spacing[rows, None], spacing[neighbour])
        keys.append(_edge_keys(np.nonzero(near)[0] + start, neighbour[near], n))
    keys = unique_sorted(np.concatenate(keys))
    edges = np.stack([keys // n, keys % n], axis=1)
    return SurfaceGraph(edges, spacing, int(consistent.sum()), int((~consistent).sum()))


def _edge_keys(u, v, n):
    """Keys low * n + high of the pairs (u, v) without self-loops."""
    return pair_keys(u, v, n)[np.asarray(u) != np.asarray(v)]
