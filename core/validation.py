"""Input checks shared by every entry point: each raises ValueError with a message a user can act on."""

import math
import numbers

import numpy as np

FLOAT_DTYPES = (np.float32, np.float64)


def check_positions(positions, name="positions"):
    """Return ``positions`` as an (n, 3) float32/float64 array (no copy), or raise ValueError."""
    array = np.asarray(positions)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {array.shape}")
    if array.dtype.type not in FLOAT_DTYPES:
        raise ValueError(f"{name} must be float32 or float64, got {array.dtype}")
    first = nonfinite_rows(array)
    if first.size:
        raise ValueError(
            f"{name} contain NaN or infinite coordinates at {first.size} vertices "
            f"(first: vertex {first[0]}); fix or delete those vertices first"
        )
    return array


def nonfinite_rows(array):
    """Indices of the rows holding NaN or inf. A sum is finite unless some entry is not (or it overflows,
    which the exact check below then clears): one fast pass for the common, clean case.

    Examples
    --------
    >>> import numpy as np, core
    >>> core.nonfinite_rows(np.array([[0.0, 0, 0], [np.nan, 0, 0]])).tolist()
    [1]
    """
    with np.errstate(over="ignore", invalid="ignore"):  # huge finite coordinates may overflow the sum
        total = array.sum(dtype=np.float64)
    if np.isfinite(total):
        return np.zeros(0, dtype=np.intp)
    return np.flatnonzero(~np.isfinite(array).all(axis=1))


def bbox_diagonal(points):
    """Length of the bounding-box diagonal of (n, 3) points (0 for none). Column by column: NumPy's
    axis-0 reduction over a narrow (n, 3) array is about ten times slower."""
    if points.shape[0] == 0:
        return 0.0
    extent = [float(points[:, k].max()) - float(points[:, k].min()) for k in range(points.shape[1])]
    return math.hypot(*extent)  # scaled: no overflow or underflow at extreme coordinates


def squares_are_safe(length, dtype):
    """Whether lengths up to ``length`` (and down to a millionth of it) square without overflow or
    underflow in ``dtype``: then plain sums of squares are exact enough, else scale first."""
    info = np.finfo(dtype)
    return length == 0.0 or np.sqrt(info.tiny) * 1e6 < length < np.sqrt(info.max) / 1e6


def row_lengths(vectors, reference):
    """Euclidean lengths of the rows of (n, k) ``vectors``; ``reference`` bounds them (a bounding-box
    diagonal): at scales where squares would overflow or underflow, the rows are scaled first."""
    if squares_are_safe(reference, vectors.dtype):
        return np.sqrt(np.einsum("ij,ij->i", vectors, vectors))
    scale = vectors.dtype.type(reference)
    scaled = vectors / scale
    return np.sqrt(np.einsum("ij,ij->i", scaled, scaled)) * scale


def check_edges(edges, n_vertices):
    """Return ``edges`` as an (m, 2) integer array, or raise ValueError."""
    array = np.asarray(edges)
    if array.size == 0:
        return np.empty((0, 2), dtype=np.int64)
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"edges must have shape (m, 2), got {array.shape}")
    if not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"edges must hold integer vertex indices, got {array.dtype}")
    low, high = array.min(), array.max()
    if low < 0 or high >= n_vertices:
        bad = low if low < 0 else high
        raise ValueError(f"edges refer to vertex {bad}, but there are only {n_vertices} vertices (0..{n_vertices - 1})")
    return array


def check_fixed(fixed, n_vertices):
    """Return a boolean mask of length n from a mask or an index array (None: nothing fixed).

    An integer array as long as the vertex count holding only 0s and 1s is refused: it reads as a
    0/1 mask just as well as the indices 0 and 1. (One vertex is exempt: it has no neighbours and
    never moves, so both readings give the same result.)
    """
    if fixed is None:
        return np.zeros(n_vertices, dtype=bool)
    array = np.asarray(fixed)
    if array.dtype == bool:
        if array.shape != (n_vertices,):
            raise ValueError(f"a boolean fixed mask must have length {n_vertices}, got shape {array.shape}")
        return array.copy()
    if array.size == 0:
        return np.zeros(n_vertices, dtype=bool)
    if array.ndim != 1 or not np.issubdtype(array.dtype, np.integer):
        raise ValueError("fixed must be a boolean mask or a 1-D array of vertex indices")
    low, high = array.min(), array.max()
    if n_vertices >= 2 and array.shape[0] == n_vertices and low >= 0 and high <= 1:
        raise ValueError(
            f"fixed is an integer array of length {n_vertices} (the vertex count) holding only 0s and 1s, "
            "which could be a 0/1 mask or the vertex indices 0 and 1. For a mask pass fixed.astype(bool); "
            "for indices pass an array shorter than the vertex count, such as np.flatnonzero(mask) "
            "(on a mesh of 2 vertices, fix both with a boolean mask)"
        )
    if low < 0 or high >= n_vertices:
        raise ValueError(f"fixed vertex indices must lie in 0..{n_vertices - 1}")
    mask = np.zeros(n_vertices, dtype=bool)
    mask[array] = True
    return mask


def power_of_two_scale(points, name="points"):
    """A power of two S with max |coordinate| / S in [0.5, 1) (1 when every coordinate is 0), after
    checking that the coordinates' magnitude fits the dtype: dividing by S is then exact.

    Below the dtype's smallest normal number coordinates lose precision (subnormals); the upper
    limit leaves a factor 16 of headroom, so that moved points mapped back cannot overflow.
    """
    if points.size == 0:
        return 1.0
    largest = max(abs(float(points.max())), abs(float(points.min())))
    if largest == 0.0:
        return 1.0
    info = np.finfo(points.dtype)
    low, high = float(info.tiny), float(info.max) / 16.0
    if not low <= largest <= high:
        raise ValueError(
            f"the scale of the {name}' coordinates is out of range: their largest magnitude is {largest:.3g}, "
            f"but {points.dtype} {name} need it between {low:.3g} and {high:.3g}; rescale them into that "
            "range first (e.g. change the unit)"
        )
    return float(np.ldexp(1.0, int(np.frexp(largest)[1])))


def check_influence(influence, n_vertices):
    """Return per-vertex weights in [0, 1] as float64 (None: every vertex takes the full step)."""
    if influence is None:
        return None
    array = np.asarray(influence)
    if array.shape != (n_vertices,) or not (
        np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)
    ):
        raise ValueError(
            f"influence must be {n_vertices} numbers between 0 and 1, one per vertex, "
            f"got {array.dtype} of shape {array.shape}"
        )
    weights = array.astype(np.float64)
    if not np.all((weights >= 0.0) & (weights <= 1.0)):  # NaN fails both
        bad = int(np.flatnonzero(~((weights >= 0.0) & (weights <= 1.0)))[0])
        raise ValueError(f"influence must lie between 0 and 1, got {weights[bad]:g} at vertex {bad}")
    return weights


def check_max_deviation(value, n_vertices):
    """The deviation limit: a finite distance >= 0 (0: no limit), or one per vertex (float64 (n,))."""
    if isinstance(value, np.ndarray):
        if value.shape != (n_vertices,) or not np.all((value >= 0.0) & (value < math.inf)):
            raise ValueError(f"max_deviation per vertex must be {n_vertices} finite distances >= 0")
        return value.astype(np.float64)
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (0.0 <= value < math.inf):
        raise ValueError(f"max_deviation must be a distance >= 0 (0 for no limit), got {value!r}")
    return float(value)


def check_unit_interval(value, name):
    """Return ``value`` as a float in [0, 1], or raise ValueError."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{name} must be a number between 0 and 1, got {value!r}")
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"{name} must lie between 0 and 1, got {value}")
    return float(value)


def check_iterations(value):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"iterations must be a whole number, got {value!r}")
    if value < 0:
        raise ValueError(f"iterations must be 0 or more, got {value}")
    return int(value)


def check_tolerance(value):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value) or value < 0:
        raise ValueError(f"tolerance must be a number >= 0 (0 = always run every iteration), got {value!r}")
    return float(value)


def check_choice(value, name, choices):
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value
