"""What an open border does while the surface is smoothed.

A vertex on an open border (an edge of exactly one face) has neighbours on one side only: the umbrella
average pulls it into the surface, and the outline of an open scan shrinks and loses its shape. Rules:

* ``"free"``: every vertex averages all its neighbours (the paper's algorithm, as it stands).
* ``"curve"``: a border vertex averages only its two neighbours along the border, so the border is
  smoothed as a curve (the one-dimensional HC, with the same alpha and beta), while interior vertices
  keep all their neighbours, border ones included. Where the border is not a simple curve (a corner
  where more than two border edges meet, or a border vertex with fewer than two border neighbours) the
  vertex stays fixed. adj() is then directed: core.adjacency holds such patterns.
* ``"fixed"``: border vertices do not move (the add-on's Pin Boundary).

Border edges come from the faces: without faces there is no border to follow, and asking for a rule
other than ``"free"`` raises ValueError rather than silently smoothing as if there were none.

Examples
--------
>>> import core
>>> strip = [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]]  # a strip of two quads: every vertex on the border
>>> core.mesh.borders.border_edges(strip, 6).tolist()
[[0, 1], [0, 2], [1, 3], [2, 4], [3, 5], [4, 5]]
"""

import numpy as np

from ..adjacency import grouped_pairs

BORDERS = ("free", "curve", "fixed")


def border_edges(triangles, n_vertices):
    """(m, 2) vertex pairs (low, high), sorted, of the edges in exactly one of the (t, 3) ``triangles``.
    The diagonals of a fan-triangulated face lie in two of its triangles, so they never count."""
    triangles = np.asarray(triangles)
    index = np.int32 if n_vertices < np.iinfo(np.int32).max else np.int64
    # Each triangle's sides (corner k to corner k + 1) as (low, high), written straight into place.
    count = len(triangles)
    low, high = np.empty(3 * count, dtype=index), np.empty(3 * count, dtype=index)
    for k in range(3):
        heads, tails, side = triangles[:, k], triangles[:, (k + 1) % 3], slice(k * count, (k + 1) * count)
        np.minimum(heads, tails, out=low[side], casting="unsafe")
        np.maximum(heads, tails, out=high[side], casting="unsafe")
    proper = low != high  # a degenerate triangle's collapsed side is no edge
    if not proper.all():
        low, high = low[proper], high[proper]
    del proper
    if low.size == 0:
        return np.zeros((0, 2), dtype=index)
    indptr, columns = grouped_pairs(low, high, n_vertices)
    del low, high
    rows = np.repeat(np.arange(n_vertices, dtype=columns.dtype), np.diff(indptr))
    starts = np.flatnonzero(np.concatenate(([True], (columns[1:] != columns[:-1]) | (rows[1:] != rows[:-1]), [True])))
    once = starts[:-1][np.diff(starts) == 1]
    return np.stack([rows[once], columns[once]], axis=1)


def apply_border(border, operator, triangles, fixed, edges=None):
    """(operator, fixed) for the ``border`` rule: the umbrella (core.adjacency.Umbrella) with the border
    rows of ``"curve"``, and the fixed mask with the vertices the rule holds. ``triangles``: (t, 3) or
    None (then only ``"free"`` is possible); ``edges``: their ``border_edges``, if the caller has them."""
    if border == "free":
        return operator, fixed
    if triangles is None:
        raise ValueError(
            f"border={border!r} needs the faces (a border edge is an edge of exactly one face): pass faces=, "
            "or border='free'"
        )
    n = operator.n_vertices
    edges = border_edges(triangles, n) if edges is None else edges
    if edges.size == 0:  # closed: no border to hold
        return operator, fixed
    count = np.bincount(edges.ravel(), minlength=n)
    on_border = count > 0
    if border == "fixed":
        return operator, fixed | on_border
    curve = count == 2
    return operator.with_rows(curve, edges), fixed | (on_border & ~curve)
