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
"""

import numpy as np
import scipy.sparse as sp

BORDERS = ("free", "curve", "fixed")


def border_edges(triangles, n_vertices):
    """(m, 2) vertex pairs (low, high) of the edges in exactly one of the (t, 3) ``triangles``. The
    diagonals of a fan-triangulated face lie in two of its triangles, so they never count."""
    pairs = np.asarray(triangles)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    low, high = pairs.min(axis=1), pairs.max(axis=1)
    proper = low != high  # a degenerate triangle's collapsed side is no edge
    counts = sp.coo_matrix(
        (np.ones(np.count_nonzero(proper), dtype=np.int32), (low[proper], high[proper])),
        shape=(n_vertices, n_vertices),
    ).tocsr()
    counts.sum_duplicates()
    once = counts.data == 1
    rows = np.repeat(np.arange(n_vertices, dtype=counts.indices.dtype), np.diff(counts.indptr))
    return np.stack([rows[once], counts.indices[once]], axis=1)


def apply_border(border, operator, triangles, fixed):
    """(operator, fixed) for the ``border`` rule: the umbrella (core.adjacency.Umbrella) with the border
    rows of ``"curve"``, and the fixed mask with the vertices the rule holds. ``triangles``: (t, 3) or
    None (then only ``"free"`` is possible)."""
    if border == "free":
        return operator, fixed
    if triangles is None:
        raise ValueError(
            f"border={border!r} needs the faces (a border edge is an edge of exactly one face): pass faces=, "
            "or border='free'"
        )
    n = operator.n_vertices
    edges = border_edges(triangles, n)
    if edges.size == 0:  # closed: no border to hold
        return operator, fixed
    count = np.bincount(edges.ravel(), minlength=n)
    on_border = count > 0
    if border == "fixed":
        return operator, fixed | on_border
    curve = count == 2
    return operator.with_rows(curve, edges), fixed | (on_border & ~curve)
