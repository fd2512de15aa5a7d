"""Parts the Automatic Amount would collapse are left as they were.

On a coarse part the shape itself can read as noise. Blender's Cone (33 vertices) with noise of 0.1 median
edge lengths: GCV (core.mesh_amount) sees its apex and rim as noise, chooses 198 iterations, and the cone
shrinks to a point (Keep Sharp Edges: by a third); its noise estimate is as large as the part, so the
deviation limit does not hold it. No amount chosen for noise should do that: taking noise of standard
deviation sigma away from a part shrinks its RMS radius r (about its centroid) to sqrt(r^2 - 3 sigma^2) at
the least (isotropic noise; noise along the normals takes less). A part that ends below ``KEEP`` times that
gets its input positions back: left noisy, not harmed. sigma is core.mesh_noise's robust estimate of the
part, which a coarse shape does not inflate as it does GCV's.
"""

import numpy as np

# Of the radius noise removal can leave: a collapsing cone ends near 0 (HC) or at 0.4-0.66 (Keep Sharp Edges),
# a smoothing that keeps the shape near 1. An 8-vertex cube with noise of half its edge can end below it (its
# noise estimate is loose on so few vertices) and is then left noisy.
KEEP = 0.75


def collapsed(before, after, part_of_vertex, sigma):
    """(parts,) bool: the parts whose RMS radius in ``after`` is below KEEP x sqrt(r^2 - 3 sigma^2), r their
    radius in ``before`` and ``sigma`` (parts,) their noise.

    Examples
    --------
    >>> import numpy as np
    >>> from core.collapse import collapsed
    >>> square = np.array([[1, 1, 0], [1, -1, 0], [-1, -1, 0], [-1, 1, 0]], dtype=float)
    >>> before = np.r_[square, square + 5.0]  # two parts of radius sqrt(2)
    >>> after = np.r_[0.95 * square, 0.1 * square + 5.0]  # the first noise taken away, the second shrunk
    >>> collapsed(before, after, np.array([0, 0, 0, 0, 1, 1, 1, 1]), np.array([0.1, 0.1])).tolist()
    [False, True]
    """
    parts = sigma.size
    counts = np.maximum(np.bincount(part_of_vertex, minlength=parts), 1)
    return _radii(after, part_of_vertex, counts) < KEEP * np.sqrt(
        np.maximum(_radii(before, part_of_vertex, counts) ** 2 - 3.0 * sigma**2, 0.0)
    )


def _radii(points, part_of_vertex, counts):
    """(parts,) the RMS distance of each part's vertices to their centroid."""
    points = np.asarray(points, dtype=np.float64)
    centroids = np.stack([np.bincount(part_of_vertex, points[:, k], counts.size) for k in range(3)], axis=1)
    centroids /= counts[:, None]
    away = points - centroids[part_of_vertex]
    return np.sqrt(np.bincount(part_of_vertex, np.einsum("ij,ij->i", away, away), counts.size) / counts)
