"""Reference computations the tests check the core against; written for clarity, not speed.

Only tests use these: the core never needs the matrix T, the iteration matrix H, a dihedral angle
from four points or a face's quality on its own.
"""

import numpy as np
import scipy.sparse as sp

# --- the umbrella operator and convergence (paper section 5) ----------------------------------------


def umbrella_matrix(operator, dtype=np.float64):
    """T as CSR from an Umbrella's pattern: t_ij = 1/|adj(i)| for every edge {i, j}; rows of isolated
    vertices are empty. SciPy works out ``has_canonical_format`` itself (nothing is asserted)."""
    degree = np.diff(operator.indptr)
    weights = np.zeros(operator.n_vertices, dtype=dtype)
    np.divide(1.0, degree, out=weights, where=degree > 0, casting="unsafe")
    data = np.repeat(weights, degree)
    return sp.csr_matrix(
        (data, operator.indices.copy(), operator.indptr.copy()), shape=(operator.n_vertices, operator.n_vertices)
    )


def hc_iteration_matrix(operator, alpha, beta, movable=None):
    """H = -(1-β)T² + (2-α)(1-β)T + (1-α)βE of Theorem 5.2, on the movable vertices (dense, small meshes).

    The iteration x(k+1) = H x(k) + const converges for every start iff the spectral radius of H is < 1.
    """
    if movable is None:
        movable = ~operator.isolated
    keep = np.flatnonzero(movable)
    t = umbrella_matrix(operator)[keep][:, keep].toarray()
    identity = np.eye(keep.size)
    return -(1 - beta) * t @ t + (2 - alpha) * (1 - beta) * t + (1 - alpha) * beta * identity


def spectral_radius(matrix):
    values = np.linalg.eigvals(matrix.toarray() if sp.issparse(matrix) else matrix)
    return float(np.abs(values).max()) if values.size else 0.0


# --- triangle geometry (RFS mesh, edge swapping) -----------------------------------------------------


def _dot(x, y):
    return x[..., 0] * y[..., 0] + x[..., 1] * y[..., 1] + x[..., 2] * y[..., 2]


def dihedral_cos(points, u, v, s, t):
    """cos of the dihedral angle at edge (u, v) between triangles (u, v, s) and (u, v, t), from the
    four points alone (no face normals): pi when the faces lie flat on opposite sides of the edge,
    0 when folded onto each other; NaN for a degenerate face."""
    origin = points[u]
    e = points[v] - origin
    a = points[s] - origin
    b = points[t] - origin
    # The angle between the components of a and b perpendicular to e, through
    # (e x a).(e x b) = |e|^2 (a.b) - (e.a)(e.b) and |e x a|^2 = |e|^2 |a|^2 - (e.a)^2.
    ee, ea, eb = _dot(e, e), _dot(e, a), _dot(e, b)
    num = ee * _dot(a, b) - ea * eb
    den = np.sqrt(np.maximum(ee * _dot(a, a) - ea * ea, 0.0) * np.maximum(ee * _dot(b, b) - eb * eb, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = num / den
    cos[den == 0] = np.nan
    return np.clip(cos, -1.0, 1.0)


def dihedral(points, u, v, s, t):
    """Dihedral angle in radians (see ``dihedral_cos``)."""
    return np.arccos(dihedral_cos(points, u, v, s, t))


def face_quality(points, faces):
    """Bank & Smith quality q = 4*sqrt(3)*A / (l1^2 + l2^2 + l3^2): 1 for equilateral, 0 degenerate."""
    p0, p1, p2 = (points[faces[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
    squares = _dot(p1 - p0, p1 - p0) + _dot(p2 - p1, p2 - p1) + _dot(p0 - p2, p0 - p2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.nan_to_num(4.0 * np.sqrt(3.0) * area / squares, nan=0.0)


def unique_faces(faces):
    """Distinct faces as sorted vertex triples (int64, rows sorted), without those with a repeated vertex."""
    rows = np.sort(np.asarray(faces, dtype=np.int64).reshape(-1, 3), axis=1)
    rows = rows[(rows[:, 0] != rows[:, 1]) & (rows[:, 1] != rows[:, 2])]
    return np.unique(rows, axis=0).reshape(-1, 3)
