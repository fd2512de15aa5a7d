"""How much should a noisy mesh be smoothed? (the Automatic Amount for meshes)

With alpha = 0, k HC iterations are a linear filter of the input: every coordinate goes through the
same matrix S_k, a polynomial in the umbrella operator T (paper section 5). Too few iterations leave
noise, too many flatten the shape; the best k depends on the noise, the edge lengths and the shape's
detail. It is chosen here from the mesh alone, by generalized cross-validation (GCV) along one HC run.

First, which parts have noise at all (core.mesh.noise): GCV cannot tell a clean mesh's curvature from
noise and would smooth a Blender primitive's shape away. Clean parts (an estimate of at most
core.mesh.noise.CLEAN edge lengths: analytic shapes) and parts of at most four vertices (nothing tells
their noise from their shape) are held fixed; a mesh with nothing else gets 0 iterations. Quiet parts
(an estimate below the threshold that core.mesh.noise cannot tell from a coarse shape's detail) and
light-noise parts (below the threshold, but white) are smoothed with the others, and core.MeshSmoother
keeps their vertices within a radius of their own (core.mesh.noise.Noise.quiet_radius);
``noise_found`` says whether any part has noise (above the threshold, or light). On the parts that move:

* **Residual**: R(k) = mean over sample vertices of ((y_i - x_i(k)) . n_i)^2, the part of what the
  smoothing removed that lies along the surface normal n_i (y the input, x(k) the result after k
  iterations). Only the normal part: scan noise moves points off the surface, and a move along the
  surface changes neither the shape nor its distance to the truth. The normals are the smallest PCA
  axis of each sample vertex's 1-ring, taken on the state that minimizes the GCV of the whole
  residual (all three coordinates), so that they belong to a smoothed surface, not to the noise.
* **Degrees of freedom**: t(k) = tr(S_k) / n, estimated without forming S_k (Hutchinson): random
  +-1 vectors z go through the same HC iterations, and t = mean of z . S_k z / n.
* **GCV(k) = R(k) / (1 - t(k))^2** estimates the noise variance plus the error that is left, up to a
  constant, without knowing the noise; its minimum is the amount that leaves the least error. GCV
  is flat near its minimum, and flat in k where its resolution ends (a few iterations on lightly
  noisy meshes with sharp edges): the amount chosen is the largest k whose GCV is within
  ``TOLERANCE`` of the minimum, i.e. the most smoothing the estimate cannot tell from the best.
* The square root of the minimum GCV is the noise estimate (standard deviation along the normals),
  at most ROBUST_SIGMAS times core.mesh.noise's robust one.
* **Light noise on coarse meshes**: where that picks at most ``FINE_MAX`` iterations, whole steps at
  the given beta are too coarse to say how much smoothing is wanted: k steps smooth a low frequency
  as much as k (1 - beta) steps of the gentlest kind, and below beta 0.75 a step also overshoots the
  mesh's highest frequency (its factor 1 - 4 (1 - beta) is negative). The choice is then made once
  more on steps of beta ``FINE_BETA`` (the gentlest step that removes that frequency outright, as
  trimesh's Taubin filter does), and taken where it smooths more than the whole steps did: the whole
  steps are the most GCV could not tell from its minimum, so they bound the amount from below. The
  amount says so in its beta.

Where the noise is large against a thin part (a tube a few edges around), the amount with the least
error also shrinks that part by a few per cent; core.mesh.volume.restore_volume gives the volume back.

Big meshes:

* **Patches**: a sample vertex's residual and its entry of S_k's diagonal depend only on the rings
  HC's steps reach, and S_k's weights fall off within a few rings. From ``PATCH_FROM`` movable
  vertices up, the data run and the probes run on patches (every vertex within ``PATCH_RINGS`` rings
  of ``PATCH_SEEDS`` evenly spaced seeds), the sample vertices and the trace read on their inner
  vertices, at least ``PATCH_MARGIN`` rings from a cut: the choice costs about the same on any mesh,
  and the whole mesh is smoothed once, with the k chosen. On noisy tori of 1M and 5M vertices and a
  bunny scan subdivided to 1.8M vertices the patches choose the whole mesh's k
  (``python bench/bench_default_cost.py --vertices 5M --repeat 1 --choice``).
* **Work budget**: the smoothing costs k x vertices; k is at most ``WORK_BUDGET`` / vertices (12 at
  5M vertices, 60 at 1M; meshes of up to 300k vertices are never cut), so that on a 5M-vertex scan
  the default takes at most about three times the time of the fixed 10-iteration run. The cut costs
  error where GCV wants many iterations: on a 5M-vertex torus with noise of 0.1 % of the diagonal, 12
  iterations leave 0.029 % of the diagonal (RMS distance to the surface) where GCV's 198 leave 0.014 %
  and the fixed run 0.036 % (``python bench/bench_default_cost.py --vertices 5M --error``; bench/README.md
  has the 1M torus and a 1.8M-vertex scan). The amount says so (``capped``); the choice stops at the
  first checkpoint where GCV wants more than the cut (its noise estimate then reads GCV there, a little
  above its minimum: +0.4 % on a 1M torus).

The run stops once it is well past the chosen amount. Everything is deterministic (fixed probes,
evenly spaced sample vertices), independent of the coordinates' scale, position and orientation.
"""

import math
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..adjacency import Umbrella, umbrella_from_pairs, umbrella_operator
from ..convergence import ConvergenceWarning, DivergenceError
from ..geometry import median_edge_length, smallest_group_axes
from ..parallel import run_beside
from ..slices import as_fraction
from ..smoothing import Smoothing
from ..validation import check_fixed, check_positions, check_unit_interval
from .noise import neighbours, noise_steps

TOLERANCE = 0.005  # GCV within this fraction of its minimum counts as the minimum (see above)
MAX_ITERATIONS = 200  # the most the automatic amount chooses: bounds the cost on heavy noise and fine meshes
SAMPLE_VERTICES = 4096  # vertices the residual and normals are measured on
PROBE_ENTRIES = 60_000  # +-1 probe entries (vertices x probes) for the trace: at least 3 probes, at most 24
_MIN_NEIGHBOURS = 3  # a 1-ring needs three points to define a plane
# The runs go on patches from this many movable vertices up: PATCH_SEEDS balls of PATCH_RINGS rings, the
# trace and the residual read on vertices at least PATCH_MARGIN rings inside (where S_k sees no cut).
PATCH_FROM = 250_000
PATCH_SEEDS = 8
PATCH_RINGS = 48
PATCH_MARGIN = 16
_SEED = 20_161_999  # the probes' seed: fixed, so the choice is reproducible
FINE_MAX = 3  # choices of at most this many iterations are made again on gentler steps (see above) ...
FINE_BETA = 0.75  # ... of this beta
# The noise estimate is GCV's, at most this many times core.mesh.noise's: on coarse meshes GCV reads the
# shape as noise (up to ~5x the truth at light noise), the robust estimate never does (it reads heavy
# noise along the normals low, 0.65x at a noise of 3 edge lengths).
ROBUST_SIGMAS = 2.0
# The most work the chosen run may do, in vertex-iterations: on big meshes the iterations are cut to
# WORK_BUDGET / vertices (see the module docstring).
WORK_BUDGET = 60_000_000


@dataclass(frozen=True)
class MeshAmount:
    """The amount of HC smoothing chosen for a mesh, and the estimate behind it.

    Attributes
    ----------
    alpha, beta, iterations : float, float, int
        The HC run chosen (alpha is 0: see the module docstring).
    sigma : float
        Estimated noise: standard deviation along the normals, in the positions' units.
    edge_length : float
        Median edge length of the input (of an even sample of its edges on big meshes).
    explored : int
        Iterations the estimate ran.
    noise_found : bool
        False: no part has noise found; quiet parts are smoothed within a small radius at most.
    capped : bool
        The work budget cut the iterations: GCV wanted more (see the module docstring).
    ratio : float
        sigma / edge_length.

    Examples
    --------
    >>> import numpy as np, core
    >>> u, v = np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20))
    >>> noisy = np.c_[u.ravel(), v.ravel(), np.random.default_rng(0).normal(scale=0.01, size=400)]
    >>> edges = [(i, i + 1) for i in range(400) if i % 20 < 19] + [(i, i + 20) for i in range(380)]
    >>> amount = core.choose_amount(noisy, edges)
    >>> amount.alpha, amount.beta, round(amount.sigma, 3)  # the noise added: 0.01
    (0.0, 0.6, 0.01)
    """

    alpha: float
    beta: float
    iterations: int
    # Estimated noise, standard deviation along the normals (the positions' units): GCV's where noise was
    # found (at most ROBUST_SIGMAS times the robust one), else core.mesh.noise's robust estimate (~0 on a
    # clean mesh).
    sigma: float
    edge_length: float  # median edge length of the input
    explored: int  # iterations the estimate ran
    noise_found: bool  # False: no part has noise core.mesh.noise can tell from shape (quiet parts at most)
    capped: bool = False  # the work budget cut the iterations: GCV wanted more

    @property
    def ratio(self):
        """Noise over edge length."""
        return self.sigma / self.edge_length if self.edge_length > 0 else 0.0


def _checkpoints(limit):
    """Every iteration up to 12, then steps of ~15 %."""
    k = 1
    while k <= limit:
        yield k
        k = k + 1 if k < 12 else int(round(k * 1.15))


def _ring_normals(ring, owner, degree):
    """Unit normals at the rows: the smallest PCA axis of each row's neighbours' points ``ring`` (``owner``:
    the row each belongs to, ``degree`` each row's count of them)."""
    count = degree.size
    centre = np.stack([np.bincount(owner, ring[:, k], count) for k in range(3)], axis=1)
    centre /= degree[:, None]
    spread = ring - centre[owner]
    return smallest_group_axes(owner, spread, count)


class _Run:
    """An HC run (alpha = 0) whose state can be read at a few vertices, in the caller's vertex order."""

    def __init__(self, positions, operator, fixed, beta):
        self.smoothing = Smoothing(
            positions,
            None,
            method="hc",
            alpha=0.0,
            beta=beta,
            iterations=MAX_ITERATIONS,
            fixed=fixed,
            operator=operator,
        )
        self.order = self.smoothing.order  # None, or the cache-friendly vertex order the run works in
        self.position_of = None
        if self.order is not None:
            self.position_of = np.empty_like(self.order)
            self.position_of[self.order] = np.arange(self.order.size)

    def advance(self, count):
        self.smoothing.advance(count)

    def planar(self):
        """The current state, (3, n), in the run's own vertex order."""
        return self.smoothing.current

    def at(self, rows):
        index = rows if self.position_of is None else self.position_of[rows]
        return np.asarray(self.smoothing.current[:, index].T, dtype=np.float64)

    def snapshot(self):
        """(iterations run, a copy of the state): what ``positions`` turns back into a result."""
        return self.smoothing.done, self.smoothing.current.copy()

    def positions(self, state):
        """A snapshot's state in the caller's shape, dtype and vertex order."""
        positions = np.empty(self.smoothing.shape, dtype=self.smoothing.dtype)
        if self.order is None:
            positions[...] = state.T
        else:
            positions[self.order] = state.T
        return positions


def choose_amount(
    positions: ArrayLike,
    edges: ArrayLike | None = None,
    *,
    beta: float = 0.6,
    fixed: ArrayLike | None = None,
    operator: Umbrella | None = None,
    work_budget: float | None = None,
    patch_from: int | None = None,
) -> MeshAmount:
    """The HC amount (alpha, iterations) for a noisy mesh at the given beta: see the module docstring.

    Parameters
    ----------
    positions : (n, 3) array_like of float32 or float64
        As for ``hc_smooth``.
    edges : (m, 2) array_like of int, optional
        As for ``hc_smooth``; not read when ``operator`` is given.
    beta : float in [0, 1], default 0.6
        The beta the amount is chosen for.
    fixed : bool mask or vertex indices, optional
        Vertices that never move.
    operator : Umbrella, optional
        A prebuilt ``umbrella_operator``.
    work_budget : float, optional
        The most vertex-iterations the chosen run may do (``math.inf``: no cut; None: WORK_BUDGET).
    patch_from : int, optional
        From this many movable vertices up the choice runs on patches, below on the whole mesh (None:
        PATCH_FROM).

    Returns
    -------
    MeshAmount
        alpha = 0, the iterations chosen and the beta to run them with (the given one, or FINE_BETA
        on light noise); a mesh with nothing to smooth (no noise found, or every vertex fixed) gets 0
        iterations. Parts without noise are held fixed: the chooser's ``fixed`` mask says which
        vertices the run must keep.

    See Also
    --------
    smooth_mesh : chooses the amount this way, runs it and gives closed parts their volume back.

    Examples
    --------
    >>> import numpy as np, core
    >>> u, v = np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20))
    >>> noisy = np.c_[u.ravel(), v.ravel(), np.random.default_rng(0).normal(scale=0.01, size=400)]
    >>> edges = [(i, i + 1) for i in range(400) if i % 20 < 19] + [(i, i + 20) for i in range(380)]
    >>> amount = core.choose_amount(noisy, edges)
    >>> 0 < amount.iterations <= 200, round(amount.sigma, 3)
    (True, 0.01)
    >>> smoothed = core.smooth_mesh(noisy, edges)  # runs this amount
    >>> bool(smoothed[:, 2].std() < noisy[:, 2].std() / 3)
    True
    """
    chooser = AmountChooser(
        positions, edges, beta=beta, fixed=fixed, operator=operator, work_budget=work_budget, patch_from=patch_from
    )
    for _ in chooser.steps():
        pass
    return chooser.amount


class AmountChooser:
    """choose_amount in slices, for callers that show progress and let the user cancel: checks on
    construction; ``steps()`` prepares (the noise test, the sample vertices) and chooses, yielding the
    fraction of the largest possible run done, as core.Smoothing.steps does; once it is exhausted
    ``amount`` holds the MeshAmount. Arguments as for ``choose_amount``. ``fixed`` (set by ``steps()``)
    is the mask the smoothing must run with: the given fixed vertices and the parts held (no noise).

    Examples
    --------
    >>> import numpy as np, core
    >>> u, v = np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20))
    >>> noisy = np.c_[u.ravel(), v.ravel(), np.random.default_rng(0).normal(scale=0.01, size=400)]
    >>> edges = [(i, i + 1) for i in range(400) if i % 20 < 19] + [(i, i + 20) for i in range(380)]
    >>> chooser = core.AmountChooser(noisy, edges)
    >>> fractions = list(chooser.steps())
    >>> fractions[-1], chooser.amount == core.choose_amount(noisy, edges)
    (1.0, True)
    >>> done = chooser.result()  # the data run passed the amount on its way: no second run
    >>> bool(np.array_equal(done, core.smooth_mesh(noisy, edges, max_deviation=0.0)))
    True
    """

    def __init__(
        self,
        positions,
        edges=None,
        *,
        beta=0.6,
        fixed=None,
        operator=None,
        work_budget=None,
        patch_from=None,
    ):
        start = check_positions(positions)
        self.beta = check_unit_interval(beta, "beta")
        n = start.shape[0]
        if operator is None:
            operator = umbrella_operator(edges, n)
        elif not isinstance(operator, Umbrella) or operator.n_vertices != n:
            raise ValueError(f"operator must be a core.umbrella_operator built for {n} vertices")
        self.operator = operator
        self.work_budget = WORK_BUDGET if work_budget is None else work_budget
        self.patch_from = PATCH_FROM if patch_from is None else patch_from
        self.fine_beta = FINE_BETA  # light noise: choose again on steps of this beta (None: never)
        self.amount = None
        self.data = None  # the data run, where it ran on the whole mesh (what result() reads)
        self._given = check_fixed(fixed, n)
        self._start = start
        self._ground = None  # what every choice on this mesh stands on (_Ground), made by the first slices
        self._kept = None  # the data run's state at the amount chosen so far: the result, if the choice stays
        self._fine = None  # the choice made again on gentler steps, where it is taken (light noise)
        self.kept = 1.0  # t(k) = tr(S_k) / n at the amount chosen (1: nothing ran)

    # What the ground holds, under the names callers and tests read.
    noise = property(lambda self: self._ground.noise)
    fixed = property(lambda self: self._ground.fixed)
    edge_length = property(lambda self: self._ground.edge_length)
    trace_count = property(lambda self: self._ground.trace_count)

    def steps(self):
        if self._ground is None:
            self._ground = yield from as_fraction(
                _Ground.made(self._start, self.operator, self._given, self.patch_from), 0.0
            )
        ground = self._ground
        if ground.movable == 0:
            self.amount = MeshAmount(0.0, self.beta, 0, ground.noise.level(), ground.edge_length, 0, ground.noise.found)
        if self.amount is not None:
            yield 1.0
            return
        with warnings.catch_warnings():  # alpha = 0 lies outside Theorem 5.2's region: on purpose, see above
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.runs = [_Run(block, ground.operator, ground.fixed_there, self.beta) for block in ground.probe_blocks]
            data = _Run(ground.positions, ground.operator, ground.fixed_there, self.beta)
        # Each probe block as its run holds it: (3, n), in the run's vertex order; zero where not read.
        planar_probes = [
            np.ascontiguousarray((block * ground.read if run.order is None else (block * ground.read)[run.order]).T)
            for block, run in zip(ground.probe_blocks, self.runs)
        ]
        rows, runs, operator = ground.rows, self.runs, ground.operator
        most = most_iterations(self.operator.n_vertices, self.work_budget)
        use_normals, probe_count = ground.use_normals, ground.probe_count
        owner, neighbour = neighbours(rows, operator) if use_normals else (None, None)  # the normals' 1-rings
        degree = operator.degree[rows]
        done = 0
        steps, traces, residuals = [], [], []
        best_whole, ring, normals = math.inf, None, None
        for k in _checkpoints(MAX_ITERATIONS):
            advances = [lambda run=run, count=k - done: run.advance(count) for run in (data, *runs)]
            try:  # side by side where each runs on one thread (the patches)
                run_beside(advances, operator.indices.size)
            except DivergenceError:
                break
            done = k
            trace = sum(float(np.einsum("ij,ij->", run.planar(), planar)) for run, planar in zip(runs, planar_probes))
            t = min(trace / (probe_count * ground.trace_count), 0.999)
            state = data.at(rows)
            residual = ground.y - state
            steps.append(k)
            traces.append(t)
            residuals.append(residual)
            whole = float(np.einsum("ij,ij->", residual, residual)) / (rows.size * (1.0 - t) ** 2)
            if use_normals and whole < best_whole:  # the normals' state: kept, its normals made when read
                best_whole, ring, normals = whole, data.at(neighbour), None
            # The choice so far is read for the state it keeps (a whole mesh), or where a stop rule can
            # hold: past 1.25 times the least whole GCV's step, or past the budget (the choice is at most k).
            least = steps[int(np.argmin(_scores(residuals, traces, None)))] if k >= 12 else None
            if ground.whole or (k >= 12 and (k >= 1.25 * least or k > most)):
                if normals is None and ring is not None:
                    normals = _ring_normals(ring, owner, degree)
                chosen = _chosen(steps, _scores(residuals, traces, normals))
                if chosen == k and ground.whole:
                    self._kept = data.snapshot()
                if k >= 12 and k >= 1.5 * chosen and k >= 1.25 * least:
                    break  # well past the amount chosen
                if k >= 12 and chosen > most:
                    break  # GCV wants more than the work budget allows: the amount is the budget's
            yield k / MAX_ITERATIONS
        if normals is None and ring is not None:
            normals = _ring_normals(ring, owner, degree)
        if ground.whole:
            self.data = data
        self.amount = self._amount(steps, traces, residuals, normals, done, most)
        self.traces = dict(zip(steps, traces))  # t(k) at each checkpoint, for inspection
        self.kept = float(np.interp(self.amount.iterations, steps, traces)) if self.amount.iterations else 1.0
        light = 1 <= self.amount.iterations <= FINE_MAX and not self.amount.capped
        if self.fine_beta is not None and self.beta < self.fine_beta and light:
            fine = AmountChooser(
                self._start,
                beta=self.fine_beta,
                fixed=self._given,
                operator=self.operator,
                work_budget=self.work_budget,
                patch_from=self.patch_from,
            )
            fine._ground = ground  # the same noise, fixed vertices and samples
            for fraction in fine.steps():
                yield min(done / MAX_ITERATIONS + fraction, 0.999)
            smooths = fine.amount.iterations * (1.0 - self.fine_beta)  # a low frequency's share, as above
            if smooths > self.amount.iterations * (1.0 - self.beta):
                self._fine, self.amount, self.kept = fine, fine.amount, fine.kept
        yield 1.0

    def result(self):
        """The positions after ``amount.iterations`` HC iterations (alpha 0, ``amount.beta``, these fixed
        vertices, simultaneous) if the data run passed through them on its way, else None: then the
        caller runs them. Bit for bit what core.Smoothing gives for that run, without running it again."""
        if self._fine is not None:
            return self._fine.result()
        if self.amount is not None and self.amount.iterations == 0:
            return self._start.copy()
        if self.amount is None or self._kept is None or self._kept[0] != self.amount.iterations:
            return None
        return self.data.positions(self._kept[1])

    def _amount(self, steps, traces, residuals, normals, done, most):
        ground = self._ground
        if not steps:  # diverged at once (beta far below 0.5): no amount is safe
            return MeshAmount(0.0, self.beta, 0, 0.0, ground.edge_length, 0, True)
        score = _scores(residuals, traces, normals)
        chosen = _chosen(steps, score)
        minimum = max(float(score.min()), 0.0)
        sigma = math.sqrt(minimum) if ground.use_normals else math.sqrt(minimum / 3)
        sigma = min(sigma, ROBUST_SIGMAS * ground.noise.level())
        iterations = min(int(chosen), most)
        return MeshAmount(
            0.0, self.beta, iterations, sigma, ground.edge_length, int(done), ground.noise.found, chosen > most
        )


class _Ground:
    """What every choice on a mesh stands on, whatever its beta: the noise found and the vertices held,
    the mesh the runs go on (the whole one, or patches of it) and the sample vertices read there."""

    @classmethod
    def made(cls, start, operator, given, patch_from):
        """A generator (yields None between its passes) that returns the _Ground of a mesh."""
        ground = cls()
        ground.noise = yield from noise_steps(start, operator)
        ground.fixed = fixed_mask = given | operator.isolated | ground.noise.held()
        movable = np.flatnonzero(~fixed_mask)
        ground.movable = movable.size
        ground.edge_length = median_edge_length(start, operator)
        ground.whole = movable.size < patch_from
        if movable.size == 0:
            return ground
        yield
        # The mesh the runs go on, its fixed vertices, and the vertices read there.
        inner = None
        if ground.whole:
            ground.operator, ground.fixed_there, ground.positions = operator, fixed_mask, start
            candidates = movable
        else:
            ground.operator, ground.fixed_there, inner, vertices = _patches(operator, fixed_mask, movable)
            ground.positions = start[vertices]
            candidates = inner[~ground.fixed_there[inner]]
        del movable
        degree = ground.operator.degree
        surface_rows = candidates[degree[candidates] >= _MIN_NEIGHBOURS]
        ground.use_normals = surface_rows.size >= 8  # else (lines, tiny meshes): the whole residual
        candidates = surface_rows if ground.use_normals else candidates
        ground.rows = candidates[
            np.unique(
                np.linspace(0, candidates.size - 1, min(candidates.size, SAMPLE_VERTICES)).round().astype(np.int64)
            )
        ]
        ground.y = np.asarray(ground.positions[ground.rows], dtype=np.float64)
        ground.trace_count = ground.movable if inner is None else int(np.count_nonzero(~ground.fixed_there[inner]))
        # As many entries on the patches as on a whole mesh: three times as many chose the same iterations on
        # 1M tori and a 1.8M bunny, smooth and bumpy, at 0.01-0.3 % noise (sigma within 0.1 %).
        ground.probe_count = probe_count = int(min(24, max(3, 3 * math.ceil(PROBE_ENTRIES / (3 * ground.trace_count)))))
        probes = np.random.default_rng(_SEED).choice(
            np.array([-1.0, 1.0], start.dtype), size=(ground.operator.n_vertices, probe_count)
        )
        probes[ground.fixed_there] = 0.0  # the trace over the movable vertices only
        ground.probe_blocks = [probes[:, i : i + 3] for i in range(0, probe_count, 3)]
        ground.read = np.ones((ground.operator.n_vertices, 1), start.dtype)  # the probes are read at ...
        if inner is not None:  # ... the patches' inner vertices only
            ground.read[:] = 0.0
            ground.read[inner] = 1.0
        return ground


def most_iterations(vertices, work_budget=None):
    """The most iterations the work budget (None: WORK_BUDGET) allows on a mesh of ``vertices`` vertices (at
    least one)."""
    budget = WORK_BUDGET if work_budget is None else work_budget
    return int(max(1, min(MAX_ITERATIONS, budget // max(vertices, 1))))


def _patches(operator, fixed_mask, movable):
    """(umbrella, fixed mask, inner vertices, vertices) of the patches: every vertex within PATCH_RINGS
    rings of PATCH_SEEDS evenly spaced movable vertices, with the edges among them; inner ones lie at
    most PATCH_RINGS - PATCH_MARGIN rings from a seed (both numbered in the patches), ``vertices`` the
    patches' vertices in the mesh, increasing (the patches number them in that order)."""
    seeds = movable[np.linspace(0, movable.size - 1, PATCH_SEEDS).round().astype(np.int64)]
    levels = _rings(operator, seeds, PATCH_RINGS)
    chosen = np.sort(np.concatenate(levels))
    number = np.full(operator.n_vertices, -1, dtype=np.int64)
    number[chosen] = np.arange(chosen.size)
    owner, neighbour = neighbours(chosen, operator)
    keep = number[neighbour] >= 0
    inner = np.sort(number[np.concatenate(levels[: PATCH_RINGS - PATCH_MARGIN + 1])])
    # The operator's own pairs (a directed pattern stays directed: core.mesh.borders' curves).
    patches = umbrella_from_pairs(
        owner[keep], number[neighbour[keep]], chosen.size, symmetric=operator.symmetric or None
    )
    return patches, fixed_mask[chosen], inner, chosen


def _rings(operator, seeds, count):
    """The vertices at 0, 1, ..., ``count`` rings from the nearest of ``seeds`` (along the operator's
    rows), one array per ring."""
    reached = np.zeros(operator.n_vertices, dtype=bool)
    ring = np.unique(seeds)
    reached[ring] = True
    levels = [ring]
    for _ in range(count):
        ring = neighbours(ring, operator)[1]
        ring = np.unique(ring[~reached[ring]])
        reached[ring] = True
        levels.append(ring)
    return levels


def _scores(residuals, traces, normals):
    """GCV at every step so far: of the normal part of the residual, or (normals None) of all of it."""
    residual = np.asarray(residuals)  # (steps, rows, 3)
    if normals is None:
        squares = np.einsum("sij,sij->s", residual, residual) / residual.shape[1]
    else:
        along = np.einsum("sij,ij->si", residual, normals)
        squares = np.einsum("si,si->s", along, along) / residual.shape[1]
    return squares / (1.0 - np.asarray(traces)) ** 2


def _chosen(steps, score):
    """The largest step whose score is within TOLERANCE of the minimum."""
    within = np.flatnonzero(score <= (1.0 + TOLERANCE) * score.min())
    return steps[int(within.max())]
