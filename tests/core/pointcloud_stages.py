"""Stages of the point-cloud pipeline as one call each on plain arrays, for the tests: the exact EMST
of points in their input order, and one edge-swapping pass on a fresh mesh."""

import numpy as np

from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst
from core.pointcloud.swap import EdgeSwapper
from core.validation import power_of_two_scale


def emst(points, neighbours=12):
    """Edges (n - 1, 2) of an exact Euclidean minimum spanning tree of ``points`` (n, 3), in input
    indices: the pipeline's Borůvka tree of the distinct points, each duplicate joined to its first
    copy by a zero-length edge. ``neighbours`` is the size of the kNN cache (exact for any value >= 1).
    """
    points = np.asarray(points)
    index = NeighbourIndex(points, neighbours, scale=power_of_two_scale(points, "points"))
    edges, _ = boruvka_emst(index)
    representative = index.original[index.representative]  # each input point's first copy
    copies = np.flatnonzero(representative != np.arange(representative.size))
    duplicates = np.stack([copies, representative[copies]], axis=1)
    return np.concatenate([index.original[edges], duplicates]).astype(np.int64)


def swap_pass(points, faces, *, rounds=3):
    """One pass of edge swapping on a fresh mesh: (new faces, their edges, number of swaps); ``faces``
    is not modified."""
    swapper = EdgeSwapper(faces, points.shape[0])
    count = swapper.swap_pass(points, rounds=rounds)
    return swapper.faces, swapper.edges, count
