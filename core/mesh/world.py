"""Smoothing an object as it stands in the world: its coordinates taken through its scale (and shear).

A Blender object's vertices are in object space; what the user sees, and measures a Deviation Limit or a
report's lengths in, is world space: the object's matrix applied. Its 3x3 part L = R S (polar decomposition:
R a rotation, perhaps with a mirror; S symmetric positive definite, the stretch) gives |L d| = |S d| for every
move d, so the *frame* S x is the world-space shape up to a rotation (and a mirror) and a translation. Neither
changes a length, an angle, a volume's size or a normal's side, and the frame keeps the faces' winding (det
S > 0), so every distance, angle and volume core measures in it is the world's; the place (translation) is
left out, as it would only cost precision.

HC and the Laplacian variants are linear in the positions with weights that depend only on the edges, so in
the frame they give the object-space result exactly (to rounding) except where a length decides: the Deviation
Limit (a ball in world space is an ellipsoid in object space), the Automatic Amount's noise test and limits,
Keep Sharp Edges' angles.

Where L keeps lengths (no scale: the identity, a rotation, a mirror) the frame is None: object space is
measured as world space is, and the run is the object-space one, bit for bit. A uniform scale s gives the
frame s I (exact for a power of two).

Examples
--------
>>> import numpy as np
>>> from core.mesh import world
>>> world.frame(np.diag([2.0, 2.0, 2.0, 1.0])).tolist()
[[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]]
>>> world.frame(np.eye(4)) is None
True
>>> stretch = world.frame(np.diag([1.0, 1.0, 10.0]))
>>> local = np.array([[0, 0, 0], [0, 0, 1]], dtype=np.float32)
>>> start = world.to_frame(local, stretch)
>>> start.tolist()
[[0.0, 0.0, 0.0], [0.0, 0.0, 10.0]]
>>> world.from_frame(local, start, start + np.float32([0, 0, 0.5]), stretch).tolist()
[[0.0, 0.0, 0.05000000074505806], [0.0, 0.0, 1.0499999523162842]]
"""

import numpy as np
from numpy.typing import ArrayLike

# Squared lengths that L changes by less than this fraction are taken as kept (a rotation's matrix in single
# precision is orthonormal to ~1e-7), and a scale as uniform where its axes differ by less.
SAME_LENGTH = 1e-6
# The smallest scale along any axis, as a fraction of the largest: below it (a flattened object) a move in
# the frame has no faithful way back into object space.
SMALLEST_SCALE = 1e-6


def frame(matrix: ArrayLike) -> np.ndarray | None:
    """The stretch S (3x3 float64, symmetric positive definite) of a matrix's 3x3 part L: |S d| = |L d| for
    every d. None where L keeps lengths (rotation, mirror, identity).

    Parameters
    ----------
    matrix : (3, 3) or (4, 4) array_like
        An object's world matrix (Blender's ``matrix_world``); only its upper-left 3x3 part is read.

    Raises
    ------
    ValueError
        A matrix that is not finite, or that flattens space along an axis (a scale of zero, or below
        SMALLEST_SCALE of the largest).

    Examples
    --------
    >>> import numpy as np, core
    >>> core.world_frame(np.diag([1.0, 1.0, 10.0, 1.0])).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 10.0]]
    """
    linear = np.asarray(matrix, dtype=np.float64)[:3, :3]
    if linear.shape != (3, 3) or not np.all(np.isfinite(linear)):
        raise ValueError("the object's transform is not a finite 3x3 or 4x4 matrix")
    gram = linear.T @ linear
    squares, axes = np.linalg.eigh(gram)
    if not squares.min() > (SMALLEST_SCALE**2) * squares.max():
        raise ValueError(
            "the object's scale is zero, or nearly, along an axis: give it a scale on every axis, or apply its "
            "scale (Object > Apply > Scale)"
        )
    if np.abs(gram - np.eye(3)).max() <= SAME_LENGTH:
        return None
    mean = np.trace(gram) / 3.0
    if np.abs(gram - mean * np.eye(3)).max() <= SAME_LENGTH * mean:
        return np.sqrt(mean) * np.eye(3)  # a uniform scale
    return (axes * np.sqrt(squares)) @ axes.T


def to_frame(positions: np.ndarray, stretch: np.ndarray) -> np.ndarray:
    """Object-space ``positions`` (n, 3) in the frame ``stretch`` (``frame``'s), in their own dtype.

    Examples
    --------
    >>> import numpy as np, core
    >>> core.to_frame(np.array([[0, 0, 1]], dtype=np.float32), np.diag([1.0, 1.0, 10.0])).tolist()
    [[0.0, 0.0, 10.0]]
    """
    return (positions.astype(np.float64) @ stretch.T).astype(positions.dtype)


def from_frame(local: np.ndarray, start: np.ndarray, result: np.ndarray, stretch: np.ndarray) -> np.ndarray:
    """A run's ``result`` in the frame (from ``start``, the frame's copy of ``local``) back in object space:
    each vertex's ``local`` position plus its move taken back through ``stretch``. A vertex that did not move
    keeps ``local``'s bits.

    Examples
    --------
    >>> import numpy as np, core
    >>> stretch, local = np.diag([1.0, 1.0, 10.0]), np.array([[0, 0, 1]], dtype=np.float32)
    >>> start = core.to_frame(local, stretch)
    >>> core.from_frame(local, start, start * 0.5, stretch).tolist()
    [[0.0, 0.0, 0.5]]
    """
    moved = np.any(result != start, axis=1)
    back = local.copy()
    moves = (result[moved].astype(np.float64) - start[moved]) @ np.linalg.inv(stretch).T
    back[moved] = (local[moved].astype(np.float64) + moves).astype(local.dtype)
    return back
