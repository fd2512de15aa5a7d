"""Is there noise on a mesh? A robust estimate that is ~0 on clean modelled meshes and close to the noise
on scans, per connected part.

GCV (core.mesh.amount) cannot tell a clean mesh's curvature from noise: on a Blender primitive it finds
"noise" and smooths the shape away. This test looks at what noise does and a modelled shape does not:

* s_i = L_i . n_i, the umbrella vector L_i = mean(adj(i)) - x_i along the normal n_i of the plane
  fitted to i's neighbours (after PLANE_STEPS averages): how far i sits off its neighbours. On a
  clean surface s is the curvature times the squared edge length; it changes slowly from vertex to
  vertex, or not at all where the mesh repeats itself (every corner of a cube, every rim vertex of a
  cylinder is alike).
* r_i = s_i - median of s_j over i's neighbours j (their normals turned to agree with n_i): ~0 on
  clean surfaces. At a crease a vertex's neighbours differ, but the median follows the majority of
  them (a trifan cap's centre is one neighbour of four), and crease vertices are few where the mesh is
  dense. Noise makes every s_i independent: r is then Gaussian, of standard deviation ``GAIN`` times
  the noise.
* How much r scales the noise depends on the layout around i (valence, the neighbours' valences):
  ``layout_gains`` reads it from the umbrella's own weights, and each r is scaled to the regular
  triangle layout GAIN was tuned on (``LAYOUT_REFERENCE``), so that quads and triangles read alike.
* The noise of a part is median |r| / (0.6745 GAIN) over its sample vertices (a robust standard
  deviation: creases, corners and the odd vertex do not move it). Vertices with fewer than three
  neighbours (curves, the corners of an open grid) use the whole vector L_i - median L_j instead
  (``CURVE_GAIN``).

A part has noise when that estimate exceeds NOISE_THRESHOLD median edge lengths. Below it, light noise
and a coarse clean shape's own detail can read alike (Blender's Monkey as it comes reads 0.07 with no
noise), so a second test asks how the residual behaves: noise is uncorrelated from vertex to vertex,
and half a step towards the neighbours' mean (x + (mean(adj) - x) / 2) takes most of it away, while a
shape's detail spans several vertices and keeps more. On the tuning set the estimate after that half
step is 0.35-0.41 of the input's on every noisy mesh, 0.57-0.93 on the Monkey as it comes and
subdivided (bench/bench_noise_found.py, bench/bench_default_heldout.py). A part below the threshold
whose estimate exceeds LIGHT_FLOOR edge lengths and drops below WHITE times itself after the half step
has **light noise**: noise found, each vertex kept within LIGHT_DEVIATIONS estimates. The test needs
WHITE_SAMPLES sample vertices in the part: a few dozen read the ratio too loosely, and on a small
coarse part nearly every vertex lies on a crease, which the half step rounds like noise. Detail at the
mesh's own resolution (bumps repeating every three or four edges) is noise to this test too: nothing tells the two
apart there.

GAIN, the threshold and the light-noise constants were chosen on a tuning set of meshes and checked on
others. Everything is independent of the coordinates' scale, position and orientation, and
deterministic.
"""

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import parallel
from ..geometry import smallest_group_axes
from ..slices import to_end
from .parts import parts as connected_parts

GAIN = 1.6  # r's standard deviation over the noise's on the tuning set, each r scaled to LAYOUT_REFERENCE
# On a curve, r = L_i - (L_{i-1} + L_{i+1}) / 2 = (4 e_{i-1} + 4 e_{i+1} - 6 e_i - e_{i-2} - e_{i+2}) / 4 of
# the noise e: each coordinate has standard deviation sqrt(70) / 4 times the noise's, and the length of
# three such is chi-distributed (median 1.5382 times that).
CURVE_GAIN = math.sqrt(70.0) / 4.0 * 1.5382
# Noise found where the estimate exceeds this many median edge lengths: 1.12 times the largest estimate on
# the clean meshes it was tuned on (0.073 on Blender's Monkey as it comes; bench/bench_noise_found.py).
# Below it a part is quiet: smoothed, but within QUIET_SHARE of its size, so a clean shape read as
# light noise keeps its form, while light noise on the tuning set's scans is still smoothed.
NOISE_THRESHOLD = 0.082
# Light noise (see above): a part below NOISE_THRESHOLD whose estimate exceeds LIGHT_FLOOR edge lengths and
# drops below WHITE times itself after a half step, read on at least WHITE_SAMPLES sample vertices. WHITE
# lies between the tuning set's noisy meshes (at most 0.41) and its clean ones (at least 0.57); the floor
# below its lightest noise found (the bone at 0.1 % of the diagonal reads 0.040). A light-noise part's
# vertices move at most LIGHT_DEVIATIONS estimates: the smallest number that wins every light cell of the
# tuning set (2.5 leaves the bone at 0.25 % isotropic 6 % worse than the fixed HC default; 3-4 are alike).
LIGHT_FLOOR = 0.03
WHITE = 0.5
WHITE_SAMPLES = 256
LIGHT_DEVIATIONS = 3.0
DEGENERATE = 4  # parts of at most this many vertices have no noise to find (their shape is all they have)
CLEAN = 0.01  # a quiet part whose estimate is at most this many edge lengths is held: an analytic shape
QUIET_SHARE = 0.001  # a quiet part's vertices move at most this share of its bounding-box diagonal
SAMPLES = 4096  # sample vertices over the whole mesh ...
PART_SAMPLES = 64  # ... and at least this many (or all) in every part
# The residuals are read in pieces of consecutive sample vertices, from PIECE_FROM samples: at least this
# many a thread, at most PIECE_ROWS rows each: a piece's few rings and their lookups stay in cache (a
# 1M-vertex torus's 4,096 samples: 72 ms whole, 42 ms in two pieces on each of two threads, 64 ms in four
# on one), and reading every vertex of a big part takes memory for a piece, not for the part.
PIECES_PER_THREAD = 2
PIECE_FROM = 1024
PIECE_ROWS = 1 << 15
_MAD = 0.6745  # median |N(0, 1)|
# The planes are fitted to the rings after this many umbrella averages of the positions: noise along the
# normals as large as the edges would otherwise tilt them towards itself (a symmetric mesh stays symmetric).
PLANE_STEPS = 2
# layout_gains of an interior vertex of a regular triangle grid (valence 6: the tuning set's layout, which GAIN
# was set on), sqrt(133 / 72): each residual is scaled by this over its own vertex's, so that a quad mesh's
# noise reads as a triangle mesh's of the same noise (a fixed gain read quad grids 20 % higher).
LAYOUT_REFERENCE = math.sqrt(133.0 / 72.0)
# The floor estimate reads |r|'s FLOOR_SHARE quantile (that of |N(0, 1)| is _HALF_NORMAL_FLOOR): on noise
# alone it is the median's estimate, where a coarse shape's creases and corners reach most vertices (a cube of
# a few cuts a side: r is the crease on half of them, the noise on the rest) it is the noise's, up to a few
# times it, where the median's reads the creases (20 times it on Blender's Cube subdivided 3 cuts at 0.25 %).
# It replaces the median's only where it is below FLOOR_SPLIT times it: |r| is then no half-normal (the
# quartile of noise alone sits near the median's estimate, within a few per cent on thousands of samples and
# about 15 % on the fewest a part is read on), and the lower of two estimates of one noise would read it low.
FLOOR_SHARE = 0.25
FLOOR_SPLIT = 0.5
_HALF_NORMAL_FLOOR = 0.3186
# Where the creases reach fewer vertices (a box of nine cuts a side: a fifth of them on its creases, at six
# times the noise and more) the quartile rises with the median and reads the noise 1.3-1.7 times over. The
# floor is then the clipped estimate, if lower: samples beyond CLIP estimates are dropped and the median of
# the rest read as that of a half-normal cut at CLIP (_CLIPPED_MEDIAN), until it settles. On noise alone
# clipping drops the 1 % beyond CLIP and changes the estimate by about as much: 1.0-1.3 times the noise on
# that box, within 2 % of the median's on the noisy primitives (tests/core/test_coarse_defaults.py). It is
# read below NOISE_THRESHOLD only: heavier noise tilts the planes and gives r a long tail of its own, which
# clipping cuts (a noisy Ico Sphere of 42 vertices at half an edge: 0.6 times the median's, itself low).
CLIP = 2.5
_CLIPPED_MEDIAN = 0.6648  # median of |N(0, 1)| below CLIP: the normal's 0.5 + P(|N| < CLIP) / 4 quantile
_CLIP_ROUNDS = 20
_FEW_PARTS = 1000  # parts in vertex order up to this many are sampled part by part


@dataclass(frozen=True)
class Noise:
    """The noise found on a mesh, per connected part (parts numbered as ``part_of_vertex``)."""

    part_of_vertex: np.ndarray  # (n,) the part of each vertex
    sigma: np.ndarray  # (parts,) estimated noise, standard deviation along the normals
    edge_length: np.ndarray  # (parts,) median edge length at the sample vertices
    noisy: np.ndarray  # (parts,) bool: noise found (never on a part of at most DEGENERATE vertices)
    light: np.ndarray  # (parts,) bool: noise found below the threshold, by the half-step test
    # (parts,) the estimate read on the quieter vertices where r is no half-normal (see FLOOR_SHARE), else
    # ``sigma``: what the rules
    # that judge a finished run against the noise (core.mesh.collapse) read where shape inflates ``sigma``.
    floor: np.ndarray | None = None
    samples: np.ndarray | None = None  # (parts,) the vertices each part's estimates were read on

    @property
    def sampled(self):
        """(parts,) bool: parts whose estimates were read on a share of their vertices (None: unknown)."""
        if self.samples is None:
            return np.zeros(self.noisy.size, dtype=bool)
        return self.samples < np.bincount(self.part_of_vertex, minlength=self.noisy.size)

    @property
    def found(self):
        return bool(self.noisy.any())

    @property
    def quiet(self):
        """(n,) bool: vertices of parts without noise found."""
        return ~self.noisy[self.part_of_vertex]

    @property
    def limited(self):
        """(n,) bool: vertices whose deviation limit ``quiet_radius`` gives (quiet and light-noise parts)."""
        return (~self.noisy | self.light)[self.part_of_vertex]

    def held(self):
        """(n,) bool: vertices no smoothing should move: parts of at most DEGENERATE vertices (their shape is
        all they have) and parts whose estimate is ``CLEAN`` or less of their edge length (analytic shapes:
        Blender's primitives, CAD parts)."""
        held = np.bincount(self.part_of_vertex, minlength=self.noisy.size) <= DEGENERATE
        held |= ~self.noisy & (self.sigma <= CLEAN * self.edge_length)
        return held[self.part_of_vertex]

    def quiet_radius(self, positions, deviations):
        """(n,) the deviation limit of a run on light noise: on a part where noise is found above the
        threshold, 0 (the caller's limit applies); on a light-noise part, LIGHT_DEVIATIONS times its
        estimate; on a quiet part, ``deviations`` times its estimate, at most ``QUIET_SHARE`` of the
        part's bounding-box diagonal: where noise cannot be told from shape, no vertex moves farther
        than a share of the size no one sees."""
        parts = self.noisy.size
        low = np.full((parts, 3), np.inf)
        high = np.full((parts, 3), -np.inf)
        np.minimum.at(low, self.part_of_vertex, positions)
        np.maximum.at(high, self.part_of_vertex, positions)
        diagonal = np.sqrt(np.sum((high - low) ** 2, axis=1))
        radius = np.where(self.noisy, 0.0, np.minimum(deviations * self.sigma, QUIET_SHARE * diagonal))
        radius[self.light] = LIGHT_DEVIATIONS * self.sigma[self.light]
        return radius[self.part_of_vertex]

    def level(self):
        """The estimate for the whole mesh: over the noisy parts if there are any, else over all parts
        (each weighted by its vertices)."""
        chosen = self.noisy if self.found else np.ones(self.noisy.size, dtype=bool)
        weights = np.bincount(self.part_of_vertex, minlength=self.noisy.size)[chosen]
        return float(np.average(self.sigma[chosen], weights=weights)) if weights.sum() else 0.0


def neighbours(rows, operator):
    """(owner, neighbour): every neighbour of every row, owner the row's place in ``rows``."""
    starts, counts = operator.indptr[rows], operator.degree[rows]
    owner = np.repeat(np.arange(rows.size), counts)
    # Entry k of the result is entry k - (the owner's first k) of the owner's row.
    shift = np.repeat(starts - (np.cumsum(counts) - counts), counts)
    return owner, operator.indices[shift + np.arange(shift.size)]


def find_noise(positions, operator):
    """The Noise of a mesh: ``positions`` (n, 3), ``operator`` its core.umbrella_operator."""
    return to_end(noise_steps(positions, operator))


def noise_steps(positions, operator):
    """``find_noise`` in slices, for callers that let the user cancel: a generator that yields (None)
    between its passes and returns the Noise. Reads the positions at the sample vertices' few rings only."""
    n = operator.n_vertices
    parts, part_of_vertex = connected_parts(operator.indptr, operator.indices, n, cyclic=operator.symmetric)
    yield
    sizes = np.bincount(part_of_vertex, minlength=parts)
    rows = _sample(part_of_vertex, sizes, operator)
    yield
    sigma, edge_length, floor, counted = yield from _estimate_steps(positions, rows, operator, part_of_vertex, sizes)
    above = (sizes > DEGENERATE) & (sigma > NOISE_THRESHOLD * edge_length)
    # The half-step test, on the parts it can find light noise in only (none on most noisy scans).
    light = ~above & (counted >= WHITE_SAMPLES) & (sigma > LIGHT_FLOOR * edge_length)
    if light.any():
        yield
        owner = part_of_vertex[rows]
        asked = light[owner]
        after = (yield from _residual_rounds(positions, rows[asked], operator, halves=1))[0]
        keep = np.isfinite(after)
        light &= _group_medians(owner[asked][keep], after[keep], parts) / (_MAD * GAIN) < WHITE * sigma
    return Noise(part_of_vertex, sigma, edge_length, above | light, light, floor, counted)


def _estimate_steps(positions, rows, operator, part_of_vertex, sizes):
    """(sigma, edge_length, floor, samples) per part (``sizes``: each part's vertex count), read at the
    vertices ``rows``: the estimates of ``Noise``, and how many of its rows each part's were read on. A
    generator: yields (None) after each round of ``_residual_rounds``."""
    parts = sizes.size
    residual, edge = yield from _residual_rounds(positions, rows, operator)
    owner = part_of_vertex[rows]
    sigma, edge_length = np.zeros(parts), np.zeros(parts)
    for values, out in ((residual, sigma), (edge, edge_length)):
        keep = np.isfinite(values)
        out[:] = _group_medians(owner[keep], values[keep], parts)
    keep = np.isfinite(residual)
    floor = _group_quantiles(owner[keep], residual[keep], parts, FLOOR_SHARE) / (_HALF_NORMAL_FLOOR * GAIN)
    sigma /= _MAD * GAIN
    sigma[sizes <= DEGENERATE] = 0.0
    floor = np.where(floor < FLOOR_SPLIT * sigma, floor, sigma)  # NaN (no samples): sigma
    above = (sizes > DEGENERATE) & (sigma > NOISE_THRESHOLD * edge_length)
    clipped = _clipped(owner, residual, parts, sigma * (_MAD * GAIN)) / (_MAD * GAIN)
    floor = np.where(above, floor, np.fmin(floor, clipped))
    return sigma, edge_length, floor, np.bincount(owner[keep], minlength=parts)


def read_on_every_vertex(noise, positions, operator, asked):
    """``read_on_every_vertex_steps`` run to its end."""
    return to_end(read_on_every_vertex_steps(noise, positions, operator, asked))


def read_on_every_vertex_steps(noise, positions, operator, asked):
    """(parts,) the estimate the rules that judge a finished run read (``Noise.floor``, else ``sigma``), of
    the parts ``asked`` ((parts,) bool) read again on every vertex of them, of the others as ``noise`` has
    it. A part's estimate reads a sample of its vertices (PART_SAMPLES at the least); a rule about to give
    a part its input back on that reading (core.mesh.collapse) asks first what all of them say: on a
    part of 8,724 vertices read on about a hundred, the estimate of one noise spread over 0.38-0.48 with
    the sample's numbering, and on all of them it read 0.48.

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.mesh import noise
    >>> side = np.arange(100.0)
    >>> x, y = np.meshgrid(side, side)
    >>> flat = np.c_[x.ravel(), y.ravel(), np.random.default_rng(1).normal(0.0, 0.1, 10_000)]
    >>> grid = np.arange(10_000).reshape(100, 100)
    >>> edges = np.r_[np.c_[grid[:, :-1].ravel(), grid[:, 1:].ravel()], np.c_[grid[:-1].ravel(), grid[1:].ravel()],
    ...               np.c_[grid[:-1, :-1].ravel(), grid[1:, 1:].ravel()]]
    >>> operator = core.umbrella_operator(edges, 10_000)
    >>> found = noise.find_noise(flat, operator)
    >>> found.samples.tolist(), found.sampled.tolist()  # a third of the vertices read
    ([3334], [True])
    >>> every = noise.read_on_every_vertex(found, flat, operator, found.sampled)
    >>> found.floor.round(4).tolist(), every.round(4).tolist()
    ([0.0853], [0.0874])

    A generator: yields (None) after each round of pieces of rows (``_residual_rounds``; a 1M-vertex part
    takes some 3 s in 31 pieces), so that a caller shows progress and can cancel between them.
    """
    current = noise.sigma if noise.floor is None else noise.floor
    if not asked.any():
        return current
    sizes = np.bincount(noise.part_of_vertex, minlength=asked.size)
    rows = np.flatnonzero(asked[noise.part_of_vertex] & (operator.degree > 0))
    _, _, floor, _ = yield from _estimate_steps(positions, rows, operator, noise.part_of_vertex, sizes)
    return np.where(asked, floor, current)


def _sample(part_of_vertex, sizes, operator):
    """Evenly spaced vertices with neighbours: SAMPLES over the mesh, at least PART_SAMPLES (or all) per part."""
    want = np.minimum(sizes, np.maximum(PART_SAMPLES, np.ceil(SAMPLES * sizes / max(1, sizes.sum()))))
    stride = np.ceil(sizes / np.maximum(want, 1)).astype(np.int64)
    starts = np.cumsum(sizes) - sizes
    if sizes.size <= _FEW_PARTS and not np.any(part_of_vertex[1:] < part_of_vertex[:-1]):
        # Parts in vertex order (one part, say): every stride-th vertex of each part's run.
        runs = [np.arange(start, start + size, step) for start, size, step in zip(starts, sizes, stride)]
        rows = np.concatenate(runs) if runs else np.zeros(0, dtype=np.int64)
    else:
        order = np.argsort(part_of_vertex, kind="stable")
        rank = np.arange(order.size) - np.repeat(starts, sizes)
        rows = order[rank % stride[part_of_vertex[order]] == 0]
    return np.sort(rows[operator.degree[rows] > 0])


def _residual_rounds(positions, rows, operator, halves=0):
    """``_residuals`` of the sorted ``rows`` in pieces of consecutive rows, PIECES_PER_THREAD a thread at the
    least and PIECE_ROWS rows at most, one a thread at a time: a row's residual reads its own few rings only,
    so the pieces give the same numbers as the whole, and each piece's rings stay small (in cache, and a
    bounded memory when every vertex of a big part is read). A generator: yields (None) after each round."""
    threads = parallel.thread_count()
    count = max(threads * PIECES_PER_THREAD, -(-rows.size // PIECE_ROWS)) if rows.size >= PIECE_FROM else 1
    cuts = np.linspace(0, rows.size, count + 1).round().astype(np.int64)
    done = []
    for first in range(0, count, threads):
        pieces = range(first, min(first + threads, count))
        done += parallel.run_all(
            [lambda k=k: _residuals(positions, rows[cuts[k] : cuts[k + 1]], operator, halves) for k in pieces]
        )
        yield
    return tuple(np.concatenate(values) for values in zip(*done))


def _residuals(positions, rows, operator, halves=0):
    """(|r_i| at each row, NaN where undefined; the median length of each row's edges), of the positions
    after ``halves`` half steps towards the neighbours' mean (x + (mean(adj) - x) / 2: a whole step
    would flip, not damp, the highest frequency of a quad grid)."""
    owner, neighbour = neighbours(rows, operator)
    ring = _union(operator.n_vertices, rows, neighbour)
    # around[k]: the vertices within k + 1 rings of the rows. The positions are read (as float64) on the
    # outermost; each average reaches one ring less, and the planes' points lie within two rings.
    # adjacent[k]: ``neighbours`` of around[k], kept for the averages and the planes.
    around, adjacent = [ring], []
    for _ in range(PLANE_STEPS + 1 + halves):
        adjacent.append(neighbours(around[-1], operator))
        around.append(_union(operator.n_vertices, around[-1], adjacent[-1][1]))
    # place[k][v]: v's row in around[k] (valid for v in it), in one gather where a search would take many.
    place = [_places(operator.n_vertices, vertices) for vertices in around]
    points, at_points = np.asarray(positions[around[-1]], dtype=np.float64), place[-1]
    for step in range(halves):
        level = PLANE_STEPS + halves - step  # the average reaches around[level]
        kept = points[at_points[around[level]]]
        averaged = _averaged(points, at_points, around[level], adjacent[level][1], operator)
        points, at_points = 0.5 * (kept + averaged), place[level]
    plane, at_plane = points, at_points
    for step in range(PLANE_STEPS):
        level = PLANE_STEPS - step
        plane = _averaged(plane, at_plane, around[level], adjacent[level][1], operator)
        at_plane = place[level]

    def point_at(vertices):
        return points[at_points[vertices]]

    def plane_at(vertices):
        return plane[at_plane[vertices]]

    normals, umbrella = _planes(point_at, ring, adjacent[0], operator, plane_at)
    row_at, neighbour_at = place[0][rows], place[0][neighbour]
    surface = operator.degree[rows] >= 3

    # Surfaces: the normal part of the umbrella against its neighbours' median.
    n_row = normals[row_at]
    agree = np.sign(np.einsum("ij,ij->i", normals[neighbour_at], n_row[owner]))
    agree[agree == 0] = 1.0
    s_neighbour = np.einsum("ij,ij->i", umbrella[neighbour_at], normals[neighbour_at]) * agree
    s_row = np.einsum("ij,ij->i", umbrella[row_at], n_row)
    residual = np.abs(s_row - _group_medians(owner, s_neighbour, rows.size))

    # Curves (and the odd vertex with fewer than three neighbours): the whole umbrella vector.
    curve = ~surface
    if curve.any():
        medians = np.stack([_group_medians(owner, umbrella[neighbour_at, k], rows.size) for k in range(3)], axis=1)
        vector = umbrella[row_at] - medians
        residual[curve] = np.linalg.norm(vector[curve], axis=1) * (_MAD * GAIN / CURVE_GAIN)

    residual[surface] *= LAYOUT_REFERENCE / layout_gains(rows[surface], operator)  # as on the tuning layout
    lengths = np.linalg.norm(point_at(neighbour) - point_at(rows)[owner], axis=1)
    return residual, _group_medians(owner, lengths, rows.size)


def layout_gains(rows, operator):
    """How much each row's residual scales the noise on its layout: the length of row i of (I - U)^2, U the
    umbrella average (r_i ~ s_i - mean of s_j over adj(i), s = (U - I) e, with the median in place of the
    mean). On flat grids with unit noise along the normal, median |r| / (0.6745 times this) reads 0.99-1.04
    on every valence (quads, regular and Delaunay triangles, valence 3 to 10), where a fixed gain reads quads
    20 % above regular triangles (``LAYOUT_REFERENCE``)."""
    owner, first = neighbours(rows, operator)
    second_owner, second = neighbours(first, operator)
    weight_first = 1.0 / operator.degree[rows][owner]
    weight_second = weight_first[second_owner] / operator.degree[first][second_owner]
    weights = sp.csr_matrix(  # (I - 2U + U^2) on the rows: duplicates (paths of two steps) summed
        (
            np.concatenate([np.ones(rows.size), -2.0 * weight_first, weight_second]),
            (np.concatenate([np.arange(rows.size), owner, owner[second_owner]]), np.concatenate([rows, first, second])),
        ),
        shape=(rows.size, operator.n_vertices),
    )
    return np.sqrt(np.asarray(weights.multiply(weights).sum(axis=1)).ravel())


def _union(n, *vertex_sets):
    """The distinct vertices of ``vertex_sets`` (indices below ``n``), sorted: marked in a mask of the mesh,
    which a big mesh's few rings take in one pass where sorting them would take many."""
    mask = np.zeros(n, dtype=bool)
    for vertices in vertex_sets:
        mask[vertices] = True
    return np.flatnonzero(mask)


def _places(n, vertices):
    """(n,) int: each of ``vertices``' place in it (other entries undefined), to look places up by vertex."""
    places = np.empty(n, dtype=np.int64)
    places[vertices] = np.arange(vertices.size)
    return places


def _averaged(values, places, targets, neighbour, operator):
    """One umbrella average (each vertex to the mean of its neighbours; one without neighbours stays) at
    the sorted vertices ``targets`` (``neighbour``: their ``neighbours``), from ``values`` at the vertices
    ``places`` gives the rows of (which hold every target's neighbours): row for row the product of the
    whole mesh's averaging matrix, bit for bit."""
    degree = operator.degree[targets]
    weights = np.repeat(1.0 / np.maximum(degree, 1), degree)
    indptr = np.zeros(targets.size + 1, dtype=np.int64)
    np.cumsum(degree, out=indptr[1:])
    average = sp.csr_matrix((weights, places[neighbour], indptr), shape=(targets.size, values.shape[0]))
    moved = average @ values
    lonely = degree == 0
    moved[lonely] = values[places[targets[lonely]]]
    return moved


def _planes(point_at, ring, adjacent, operator, plane_at):
    """(normal, umbrella vector) at each vertex of ``ring`` (``adjacent``: its ``neighbours``): the smallest
    PCA axis of its neighbours' ``plane_at`` points (with itself where it has fewer than three), and
    mean(adj) - x of ``point_at``."""
    owner, neighbour = adjacent
    few = np.flatnonzero(operator.degree[ring] < 3)
    owner_all = np.concatenate([owner, few])
    spots = plane_at(np.concatenate([neighbour, ring[few]]))
    counts = np.bincount(owner_all, minlength=ring.size).astype(np.float64)
    centre = np.stack([np.bincount(owner_all, spots[:, k], ring.size) for k in range(3)], axis=1) / counts[:, None]
    spread = spots - centre[owner_all]
    normals = smallest_group_axes(owner_all, spread, ring.size)
    degree = operator.degree[ring].astype(np.float64)
    around = point_at(neighbour)
    mean = np.stack([np.bincount(owner, around[:, k], ring.size) for k in range(3)], axis=1)
    umbrella = mean / np.maximum(degree, 1.0)[:, None] - point_at(ring)
    return normals, umbrella


def _clipped(owner, values, groups, start):
    """The median of ``values`` per group (NaN: no value), of those within CLIP estimates (``start``: the plain
    medians), read as a half-normal's cut at CLIP: on |r| the clipped median, in the units of the plain one."""
    median, valid = start, np.isfinite(values)
    for _ in range(_CLIP_ROUNDS):
        kept = valid & (values <= CLIP * median[owner] / _MAD)
        clipped = _group_quantiles(owner[kept], values[kept], groups, 0.5) * (_MAD / _CLIPPED_MEDIAN)
        clipped = np.where(np.isfinite(clipped), clipped, median)
        if np.allclose(clipped, median, rtol=1e-9, atol=0.0):
            break
        median = clipped
    return clipped


def _group_quantiles(owner, values, groups, share):
    """The ``share`` quantile of ``values`` per group (linear between the two nearest); NaN for an empty group."""
    out = np.full(groups, np.nan)
    if owner.size == 0:
        return out
    order = np.lexsort((values, owner))
    counts = np.bincount(owner, minlength=groups)
    starts = np.cumsum(counts) - counts
    has = counts > 0
    place = share * (counts[has] - 1)
    low = np.floor(place).astype(np.int64)
    high = np.minimum(low + 1, counts[has] - 1)
    ordered = values[order]
    part = place - low
    out[has] = (1.0 - part) * ordered[starts[has] + low] + part * ordered[starts[has] + high]
    return out


def _group_medians(owner, values, groups):
    """The median of ``values`` per group (``owner`` in [0, groups)); NaN for an empty group."""
    return _group_quantiles(owner, values, groups, 0.5)
