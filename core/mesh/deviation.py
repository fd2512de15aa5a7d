"""The deviation map: how far each vertex moved along its normal, and a colour for it.

A vertex's deviation is its signed move along the input's unit area-weighted vertex normal,
(result - start) . n_start: positive outwards (where the normal points), negative inwards; 0 for a
vertex without a normal (no face touches it). Its colour comes from a diverging ramp centred on 0
(blue inwards, near white for no move, red outwards; ColorBrewer's RdBu), symmetric about 0.

The ramp spans ±``extent``, the 99th percentile of |deviation| over the vertices that moved, not the
largest move: one spike would otherwise leave every other vertex near white. The 1 % beyond it take
the end colours; the map keeps the true extremes (``low``, ``high``) for the legend.

Examples
--------
>>> import numpy as np, core
>>> start = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
>>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
>>> result = start.copy()
>>> result[1] += [0.1, 0.0, 0.0]  # outwards, along its normal
>>> result[2] += [0.0, -0.2, 0.0]  # inwards
>>> deviation_map = core.deviation_map(start, result, faces)
>>> deviation_map.deviation.round(3).tolist()
[0.0, 0.1, -0.2, 0.0]
>>> deviation_map.legend()
'deviation map -0.2 to +0.2 (blue: inwards, red: outwards)'
"""

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..validation import check_positions
from .metrics import measure_input

# The ramp's anchors in sRGB, from -extent to +extent: ColorBrewer RdBu (7 classes), blue first.
RAMP_ANCHORS = np.array(
    [
        (33, 102, 172),
        (103, 169, 207),
        (209, 229, 240),
        (247, 247, 247),
        (253, 219, 199),
        (239, 138, 98),
        (178, 24, 43),
    ],
    dtype=np.float64,
)
_STEPS = 255  # colours in the lookup table: odd, so that 0 falls on the middle entry (near white) exactly
PERCENTILE = 99.0  # the share of moved vertices the ramp spans before it saturates


def _lookup_table(linear):
    where = np.linspace(0.0, 1.0, len(RAMP_ANCHORS))
    at = np.linspace(0.0, 1.0, _STEPS)
    table = np.ones((_STEPS, 4), dtype=np.float32)
    for channel in range(3):
        table[:, channel] = np.interp(at, where, RAMP_ANCHORS[:, channel]) / 255.0
    if linear:  # the sRGB transfer function, inverted (IEC 61966-2-1)
        rgb = table[:, :3]
        table[:, :3] = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    return table


_TABLES = {False: _lookup_table(False), True: _lookup_table(True)}


@dataclass(frozen=True)
class DeviationMap:
    """A deviation map as ``deviation_map`` makes it.

    Attributes
    ----------
    deviation : (n,) float ndarray
        The signed move of each vertex along its input normal, in the positions' dtype and units.
    colors : (n, 4) float32 ndarray
        RGBA in [0, 1] (alpha 1), as ``deviation_colors`` gives them: sRGB-encoded, or linear.
    extent : float
        The ramp spans -extent to +extent (the legend); 0 when nothing moved along a normal.
    low, high : float
        The most negative and the most positive deviation (0 when none is).

    Examples
    --------
    >>> import numpy as np, core
    >>> before = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    >>> deviation_map = core.deviation_map(before, before + [0, 0, 0.1], [[0, 1, 2]])
    >>> deviation_map.deviation.round(3).tolist(), deviation_map.extent
    ([0.1, 0.1, 0.1], 0.1)
    >>> deviation_map.legend(lambda x: f"{x * 1000:g} mm")
    'deviation map -100 mm to +100 mm (blue: inwards, red: outwards)'
    """

    deviation: np.ndarray
    colors: np.ndarray
    extent: float
    low: float
    high: float

    def legend(self, length=None):
        """The ramp's range in words, with the extremes where they lie beyond it. ``length`` formats a
        length (a positive number) for a reader, e.g. with units; default: three significant digits.

        Examples
        --------
        >>> import numpy as np, core
        >>> deviation = np.r_[np.linspace(-0.1, 0.1, 199), 0.5]
        >>> colors = core.deviation_colors(deviation, 0.1)
        >>> core.DeviationMap(deviation, colors, 0.1, -0.1, 0.5).legend(lambda x: f"{x * 1000:.3g} mm")
        'deviation map -100 mm to +100 mm (blue: inwards, red: outwards; largest +500 mm)'
        """
        length = length or (lambda value: f"{value:.3g}")
        text = f"deviation map -{length(self.extent)} to +{length(self.extent)} (blue: inwards, red: outwards"
        beyond = [f"-{length(-self.low)}"] if -self.low > self.extent else []
        beyond += [f"+{length(self.high)}"] if self.high > self.extent else []
        return text + (f"; largest {', '.join(beyond)})" if beyond else ")")


def normal_deviation(before: ArrayLike, after: ArrayLike, faces=None, *, normals=None) -> np.ndarray:
    """Each vertex's signed move along its input normal: (after - before) . n_before.

    Parameters
    ----------
    before, after : (n, 3) array_like of float32 or float64
        The input and the result, vertex for vertex.
    faces : optional
        As for ``core.geometry.fan_triangles``: the faces whose area-weighted normals (of ``before``) are
        the vertex normals. None (and no ``normals``): every vertex gets 0.
    normals : (n, 3) array_like, optional
        The input's unit vertex normals, if the caller has them (``core.mesh.metrics.measure_input`` makes
        them); zero rows for vertices without one. Then ``faces`` is not looked at.

    Returns
    -------
    (n,) ndarray in ``before``'s dtype
        Positive outwards (where the normal points), negative inwards, 0 without a normal.

    Raises
    ------
    ValueError
        Shapes that differ or are not (n, 3), NaN or infinite coordinates, faces that refer to vertices
        that do not exist.

    Examples
    --------
    >>> import numpy as np, core
    >>> before = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    >>> after = before + np.float32([0.1, 0.0, 0.3])  # every vertex: 0.3 up, 0.1 sideways
    >>> core.normal_deviation(before, after, [[0, 1, 2]]).astype(float).round(3).tolist()
    [0.3, 0.3, 0.3]
    >>> core.normal_deviation(before, after).tolist()  # no faces: no normals
    [0.0, 0.0, 0.0]
    """
    before, after = check_positions(before, "before"), check_positions(after, "after")
    if before.shape != after.shape:
        raise ValueError(f"before and after must have the same shape, got {before.shape} and {after.shape}")
    if normals is None:
        if faces is None:
            return np.zeros(before.shape[0], dtype=before.dtype)
        normals = measure_input(before, faces, closed=False).normals
    normals = np.asarray(normals)
    if normals.shape != before.shape:
        raise ValueError(f"normals must have the shape of before, {before.shape}, got {normals.shape}")
    moves = after - before
    return np.einsum("ij,ij->i", moves, normals.astype(before.dtype, copy=False))


def deviation_extent(deviation: ArrayLike) -> float:
    """The ramp's half range: the ``PERCENTILE``-th percentile of |deviation| over the nonzero ones (a
    value among them), 0 if all are 0. Vertices that did not move (fixed, unselected) do not narrow it.

    Examples
    --------
    >>> import numpy as np, core
    >>> deviation = np.r_[np.zeros(500), np.linspace(-1, 1, 200), 40.0]  # one spike
    >>> core.deviation_extent(deviation)
    1.0
    """
    magnitude = np.abs(np.asarray(deviation))
    magnitude = magnitude[magnitude > 0]
    if not magnitude.size:
        return 0.0
    rank = min(magnitude.size - 1, int(np.ceil(PERCENTILE / 100.0 * magnitude.size)) - 1)
    return float(np.partition(magnitude, rank)[rank])


def deviation_colors(deviation: ArrayLike, extent: float, linear: bool = False) -> np.ndarray:
    """The ramp's colours of ``deviation``: RGBA (n, 4) float32 in [0, 1], alpha 1, sRGB-encoded (as an
    image or a byte colour holds them) or, ``linear``, in linear RGB (as Blender's float colours do).

    -extent and below are blue (#2166ac), 0 near white (#f7f7f7), +extent and above red (#b2182b); in
    between, 255 steps of ColorBrewer's RdBu. An ``extent`` of 0 colours everything near white.

    Examples
    --------
    >>> import core
    >>> (core.deviation_colors([-2.0, 0.0, 0.5, 1.0], extent=1.0) * 255).round().astype(int).tolist()
    [[33, 102, 172, 255], [247, 247, 247, 255], [246, 178, 147, 255], [178, 24, 43, 255]]
    """
    deviation = np.asarray(deviation)
    table = _TABLES[bool(linear)]
    middle = _STEPS // 2
    if not extent > 0:
        return np.repeat(table[middle : middle + 1], deviation.size, axis=0)
    scale = deviation.dtype.type(middle / extent) if deviation.dtype.kind == "f" else middle / extent
    index = deviation * scale  # a new array, rounded to the nearest step in place
    np.rint(index, out=index)
    np.clip(index, -middle, middle, out=index)
    index += middle
    return np.take(table, index.astype(np.intp), axis=0)


def deviation_map(before: ArrayLike, after: ArrayLike, faces=None, *, normals=None, linear=False) -> DeviationMap:
    """The deviation map of a smoothing run: ``normal_deviation``, its colours and its legend.

    Parameters are those of ``normal_deviation``; ``linear`` as for ``deviation_colors``.

    Returns
    -------
    DeviationMap

    Examples
    --------
    >>> import numpy as np, core
    >>> before = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    >>> after = before + [[0, 0, -0.5], [0, 0, 0.25], [0, 0, 0]]
    >>> deviation_map = core.deviation_map(before, after, [[0, 1, 2]])
    >>> deviation_map.extent, deviation_map.low, deviation_map.high
    (0.5, -0.5, 0.25)
    >>> deviation_map.colors.shape
    (3, 4)
    """
    deviation = normal_deviation(before, after, faces, normals=normals)
    extent = deviation_extent(deviation)
    return DeviationMap(
        deviation=deviation,
        colors=deviation_colors(deviation, extent, linear),
        extent=extent,
        low=min(0.0, float(deviation.min())) if deviation.size else 0.0,
        high=max(0.0, float(deviation.max())) if deviation.size else 0.0,
    )
