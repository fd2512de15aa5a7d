"""Keep the enclosed volume: move the smoothed vertices of each closed part a uniform distance along
their normals until the part encloses the volume it had before smoothing.

Every low-pass filter moves a curved surface towards its centres of curvature: HC far less than the
Laplacian, but where the noise is large against a thin part (a tube a few edges around) the smoothing
that removes it best also takes a few per cent of the part's volume. A uniform offset along the
normals gives that back without changing the shape's detail (unlike a scaling about a centre, which
moves far-away vertices most).

The volume of a part after an offset d along the (area-weighted, unit) vertex normals is a cubic in
d: a first pass over the triangles makes the normals, the volumes before and after and the areas, a
second the cubic's other coefficients, and Newton steps from d = 0 solve it. A part whose volume
barely changed (the offset would stay under NEGLIGIBLE times the caller's ``limit``) needs no second
pass: on big dense meshes that is the rule.

The offset gives back what smoothing took, a little, and nothing else: it is bounded. A part that
smoothing collapsed (too small to smooth, flattened: it kept less than KEPT of its volume) has a cubic
whose root lies far away or nowhere, and following it would blow the part up; such a part keeps its
smoothed shape. Only closed parts with more than DEGENERATE vertices and a volume are restored, each
on its own; no offset grows a part's bounding box by more than GROWTH, and a caller's ``limit`` bounds
it further (the mesh pipeline passes NOISE_OFFSETS times the estimated noise).
"""

from dataclasses import dataclass

import numpy as np

from ..geometry import (
    centroid,
    corner_rows,
    cross,
    dot,
    in_rounds,
    index_dtype,
    normals_and_measures,
    part_sums,
)
from ..parallel import TRIANGLE_BLOCK, VECTOR_BLOCK
from ..slices import to_end
from . import topology

_NEWTON_STEPS = 6  # at most; the volume is a cubic in the offset, Newton from 0 needs two or three
_RELATIVE_ACCURACY = 1e-12
_SETTLED = 1e-6  # a root Newton left further than this (relative to the volume) is no root
_FLAT = 1e-6  # a part enclosing less than this times its box diagonal cubed has no volume to keep
DEGENERATE = 4  # parts of at most this many vertices have no volume worth keeping (a tetrahedron at most)
GROWTH = 0.01  # the most an offset may grow a part's bounding box, along any axis (relative)
KEPT = 0.5  # a part that kept less than this share of its volume collapsed: it is not restored
# The mesh pipeline's limit, in noise deviations: the offsets that give back what HC took measure 0.01-0.3
# noise deviations on dense meshes, up to 0.75 on a coarse tube (noise 0.2-1 edge lengths).
NOISE_OFFSETS = 1.0
# A part whose volume changed so little that the offset giving it back would stay under this share of
# ``limit`` keeps its smoothed shape: the offset would not matter, and finding it takes a pass.
NEGLIGIBLE = 1e-3
BLOCK = TRIANGLE_BLOCK  # triangles per block: bounds the temporaries (a few MB a block, one block per thread)
_VERTEX_BLOCK = VECTOR_BLOCK  # vertices per block


@dataclass(frozen=True)
class Before:
    """What the volume restore needs of the positions before smoothing (``measure_before``)."""

    centre: np.ndarray  # (3,) the point the volumes are taken about
    volumes: np.ndarray  # (parts,) each part's enclosed volume, times 6
    low: np.ndarray  # (parts, 3) each part's bounding box
    high: np.ndarray


def measure_before(before, triangles, surface):
    """The Before of (n, 3) positions with the (t, 3) ``triangles`` and their core.mesh.topology.surface: one
    thread's work, which the mesh pipeline does in the background while it chooses the amount."""
    return to_end(_before_steps(np.asarray(before), np.asarray(triangles), surface))


def _before_steps(before, triangles, surface):
    """measure_before in slices (yields between blocks of triangles)."""
    planar = as_planar(before)
    low, high = part_boxes(planar, surface.part_of_vertex, surface.used, surface.parts)
    centre = centroid(before)
    volumes = yield from volume_steps(planar, triangles, surface.part_of_vertex, surface.parts, centre)
    return Before(centre, volumes, low, high)


def volume_steps(planar, triangles, part_of_vertex, parts, centre):
    """Per part (parts,) the volume its triangles enclose about ``centre``, times 6, of (3, n) planar
    positions (a triangle counts to its first corner's part), in slices (yields between blocks)."""
    volumes = np.zeros(parts)
    for start in range(0, len(triangles), BLOCK):
        block = np.ascontiguousarray(triangles[start : start + BLOCK].T, dtype=index_dtype(planar.shape[1]))
        a, b, c = corner_rows(planar, block, centre)
        volumes += part_sums([dot(a, cross(b, c))], part_of_vertex, block, parts)[0]
        yield
    return volumes


def as_planar(points):
    """A (3, n) C-contiguous copy of (n, 3) ``points``, in their dtype."""
    return np.ascontiguousarray(points.T)


def cubic_steps(after, normals, triangles, part_of_vertex, parts, centre, measures=False):
    """(c1, c2, c3) in slices, of (3, n) planar positions and normals: per part, (3, parts), the
    coefficients beyond c0 (the volume, from normals_and_measures) of its volume after an offset d along
    ``normals``: V(d) = c0 + c1 d + c2 d^2 + c3 d^3 (times 6). Each triangle's signed tetrahedron volume
    det(a, b, c) / 6 is a cubic in d: with b x c, n_b x c + b x n_c and n_b x n_c, its coefficients
    are a . (b x c), n_a . (b x c) + a . (n_b x c + b x n_c), n_a . (n_b x c + b x n_c) + a . (n_b x n_c)
    and n_a . (n_b x n_c). ``measures``: (c0, area, c1, c2, c3), (5, parts), with normals_and_measures'
    measures from the same pass (the same numbers: the same blocks, terms and sums)."""

    def block_sums(start, stop):
        block = np.ascontiguousarray(triangles[start:stop].T, dtype=index_dtype(after.shape[1]))
        a, b, c = corner_rows(after, block, centre)
        na, nb, nc = corner_rows(normals, block)
        first, second, third = cross(b, c), cross(nb, c), cross(nb, nc)
        second += cross(b, nc)
        terms = [dot(na, first) + dot(a, second), dot(na, second) + dot(a, third), dot(na, third)]
        if measures:
            twice = cross(b - a, c - a)
            terms = [dot(a, first), np.sqrt(dot(twice, twice))] + terms
        return part_sums(terms, part_of_vertex, block, parts)

    total = np.zeros((5 if measures else 3, parts))
    for sums in in_rounds(block_sums, len(triangles), BLOCK):
        for block in sums:
            total += block
        yield
    return total


def restore_volume(before, after, triangles, movable=None, limit=None):
    """``after`` with each closed part's enclosed volume set back to its volume in ``before``, by a
    uniform offset of that part's movable vertices along their normals, within bounds. Returns
    (positions, offsets) with positions float64 and offsets the distance per part (same units as the
    positions).

    ``triangles`` (t, 3), consistently oriented; ``movable`` a boolean mask (default: every vertex);
    ``limit`` the largest offset allowed (None: no limit but the bounding box's). A part is left as it
    is where it is open (not every edge in two faces, in opposite directions), has at most
    ``DEGENERATE`` vertices or no volume (nothing to give back), has no movable vertex, kept less than
    ``KEPT`` of its volume (collapsed), where the offset would be negligible (under ``NEGLIGIBLE`` times
    ``limit``: the volume change over the area says so before the cubic is made), or where the volume
    has no root within reach (an offset that does not grow the volume, Newton that does not settle).
    An offset outwards never makes the part's bounding box more than ``GROWTH`` larger than its box in
    ``before`` along any axis; inwards it is at most half the part's thinnest side; either way at most
    ``limit``: a root beyond that is clipped to it.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh import metrics, volume
    >>> positions = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    >>> triangles = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    >>> shrunk = 0.95 * positions  # an octahedron
    >>> restored, offsets = volume.restore_volume(positions, shrunk, triangles)
    >>> [round(float(metrics.enclosed_volume(p, triangles)), 4) for p in (positions, shrunk, restored)]
    [1.3333, 1.1432, 1.3333]
    >>> offsets.round(4).tolist()  # one part, moved this far along its normals
    [0.05]
    """
    return to_end(restore_steps(before, after, triangles, movable, limit))


def restore_steps(
    before, after, triangles, movable=None, limit=None, dtype=np.float64, surface=None, measured=None, normals=None
):
    """``restore_volume`` in slices, for callers that let the user cancel: a generator that yields (None)
    between its passes and returns (positions in ``dtype``, offsets); the same numbers (float64 math,
    cast to ``dtype`` at the end). ``surface``: the triangles' core.mesh.topology.surface, and ``measured``:
    ``measure_before(before, triangles, surface)``, if the caller has them. ``normals``: (3, n) unit
    directions to offset along instead of ``after``'s vertex normals (core.mesh.in_place keeps a surface
    along those of the surface it kept: offsets along them keep every vertex on its line; scaled in place).
    Beside its result it holds the float64 normals, a planar copy of the positions after (in their dtype)
    and a few bytes a vertex; the rest works in blocks of triangles."""
    before, after, triangles = np.asarray(before), np.asarray(after), np.asarray(triangles)
    n = after.shape[0]
    if triangles.size == 0:
        return np.array(after, dtype=dtype), np.zeros(0)
    movable = np.ones(n, bool) if movable is None else np.asarray(movable, bool)
    if surface is None:
        surface = topology.surface(triangles, n)
        yield
    if measured is None:
        measured = yield from _before_steps(before, triangles, surface)
    parts, part_of_vertex, used, closed = surface.parts, surface.part_of_vertex, surface.used, surface.closed
    sizes = np.bincount(part_of_vertex[used], minlength=parts)
    planar_after = as_planar(after)
    low_after, high_after = part_boxes(planar_after, part_of_vertex, used, parts)
    extent, centre, target = measured.high - measured.low, measured.centre, measured.volumes
    yield
    cubic, given = None, normals is not None
    if not given:
        measuring = normals_and_measures(planar_after, triangles, part_of_vertex, parts, centre, BLOCK)
        normals, (c0, area) = yield from measuring
    normals *= movable
    if given:  # the directions are known first: the measures and the cubic in one pass
        c0, area, *cubic = yield from cubic_steps(
            planar_after, normals, triangles, part_of_vertex, parts, centre, measures=True
        )
    outward, inward = offset_bounds(extent, high_after - low_after, limit)
    has_movable = np.bincount(part_of_vertex[movable & used], minlength=parts) > 0
    eligible = eligible_parts(closed & has_movable, sizes, target, extent, c0, area, limit)
    if not eligible.any():
        return np.array(after, dtype=dtype), np.zeros(parts)
    if cubic is None:
        cubic = yield from cubic_steps(planar_after, normals, triangles, part_of_vertex, parts, centre)
    c1, c2, c3 = cubic
    del planar_after
    offsets = solve_offsets(target, (c0, c1, c2, c3), eligible, inward, outward)
    result = np.empty((n, 3), dtype=dtype)
    for start in range(0, n, _VERTEX_BLOCK):
        rows = slice(start, start + _VERTEX_BLOCK)
        result[rows] = moved_along(after[rows], normals[:, rows], offsets[part_of_vertex[rows]])
    return result, offsets


def offset_bounds(extent, extent_after, limit=None):
    """(outward, inward): per part the largest offset each way, of its (parts, 3) bounding-box sides before
    (``extent``) and after smoothing. An offset d moves every vertex by at most |d|: outwards, each side of
    the box grows by at most 2 d; inwards the box does not grow, and half the part's thinnest side bounds d
    (it would turn inside out). ``limit`` bounds both."""
    outward = np.maximum(((1.0 + GROWTH) * extent - extent_after).min(axis=1), 0.0) / 2.0
    inward = extent_after.min(axis=1) / 2.0
    if limit is not None:
        outward, inward = np.minimum(outward, float(limit)), np.minimum(inward, float(limit))
    return outward, inward


def eligible_parts(candidates, sizes, target, extent, c0, area, limit=None):
    """(parts,) bool: the parts whose volume is given back, of the ``candidates`` (closed, with a movable
    vertex), their used vertices ``sizes``, volumes before (``target``) and after (``c0``), times 6, box
    sides before and areas (times 2): more than DEGENERATE vertices, a volume, kept more than KEPT of it,
    and an offset that is not negligible against ``limit``."""
    eligible = candidates & (sizes > DEGENERATE)
    eligible &= np.abs(target) > 6.0 * _FLAT * np.linalg.norm(extent, axis=1) ** 3
    # Smoothing that took more than half the volume collapsed the part (or turned it inside out): no
    # uniform offset mends that, and one that tried would balloon it. (Same sign as target: c0 / target.)
    eligible &= c0 * np.sign(target) > KEPT * np.abs(target)
    if limit is not None:  # the offset that gives the volume back, about its change over the area, is negligible
        eligible &= np.abs(target - c0) > NEGLIGIBLE * float(limit) * 3.0 * area
    return eligible


def solve_offsets(target, cubic, eligible, inward, outward):
    """(parts,) offsets: per ``eligible`` part the root of target = c0 + c1 d + c2 d^2 + c3 d^3 (``cubic``:
    (c0, c1, c2, c3)) by Newton steps from 0, clipped to [-inward, outward]; 0 where the volume does not
    grow along the normals or Newton does not settle near a root."""
    c0, c1, c2, c3 = cubic
    eligible = eligible & (c1 > 0.0)  # the volume grows as the surface moves along its normals
    offsets = np.zeros(len(target))
    for _ in range(_NEWTON_STEPS):
        d = offsets
        missing = target - (c0 + d * (c1 + d * (c2 + d * c3)))
        slope = c1 + d * (2.0 * c2 + 3.0 * d * c3)
        step = eligible & (slope > 0.0) & np.isfinite(missing)
        settled = np.abs(missing) <= _RELATIVE_ACCURACY * np.abs(target)
        if np.all(settled | ~step):
            break
        offsets = offsets + np.where(step & ~settled, missing / np.where(step, slope, 1.0), 0.0)
    missing = target - (c0 + offsets * (c1 + offsets * (c2 + offsets * c3)))
    # A root is sensible where Newton settled near it (the volume a cubic: from 0 it takes two or three steps).
    sensible = eligible & np.isfinite(offsets) & (np.abs(missing) <= _SETTLED * np.abs(target))
    return np.where(sensible, np.clip(offsets, -inward, outward), 0.0)


def moved_along(after, normals, offsets):
    """(m, 3) float64: (m, 3) positions ``after`` moved by ``offsets`` (m,) along their (3, m) ``normals``."""
    return np.asarray(after, dtype=np.float64) + normals.T * offsets[:, None]


def part_boxes(planar, part_of_vertex, used, parts):
    """(low, high) corners of each part's bounding box, float64 (parts, 3) each, of (3, n) points."""
    low = np.full((parts, 3), np.inf)
    high = np.full((parts, 3), -np.inf)
    for start in range(0, planar.shape[1], _VERTEX_BLOCK):
        rows = slice(start, start + _VERTEX_BLOCK)
        block, owner, inside = planar[:, rows], part_of_vertex[rows], used[rows]
        if not inside.all():
            block, owner = block[:, inside], owner[inside]
        if owner.size and owner[0] == owner[-1] and np.all(owner == owner[0]):  # one part: a plain min and max
            low[owner[0]] = np.minimum(low[owner[0]], block.min(axis=1))
            high[owner[0]] = np.maximum(high[owner[0]], block.max(axis=1))
        elif owner.size:
            for j in range(3):
                np.minimum.at(low[:, j], owner, block[j])
                np.maximum.at(high[:, j], owner, block[j])
    empty = ~np.isfinite(low[:, 0])  # a part without triangles (a loose vertex) has no box
    low[empty] = high[empty] = 0.0
    return low, high
