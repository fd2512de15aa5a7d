"""smooth_point_cloud: HC smoothing of a bare point set through its RFS mesh (paper section 7).

Pipeline: distinct points -> exact EMST -> SDG -> RFS mesh -> ``rounds`` rounds of HC steps with a
pass of edge swapping between consecutive rounds -> moved points (a swap pass after the last round
could not move any point, so there is none). HC's o (original points) stays the input throughout,
so the rounds together behave like one HC run whose mesh adapts between steps. From the second round
on, each point takes a share of every step's move that follows its curvature against the noise (the
local amount, core.pointcloud.local_amount).
"""

import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from ..adjacency import umbrella_operator
from ..memory import reusing
from ..smoothing import Cancelled, Smoothing
from ..validation import check_fixed, check_positions, check_unit_interval, power_of_two_scale
from .local_amount import local_influence, sampled_curvature, thinning
from .noise import NoiseEstimate, estimate_noise, matched_alpha, steps_per_round
from .rfs import RFSMesh, rfs_steps
from .sdg import reach_gap_problem, surface_description_graph
from .spanning_tree import NeighbourIndex, emst_steps
from .swap import EdgeSwapper


@dataclass
class PointCloudReport:
    """What a point-cloud run built and did (``smooth_point_cloud(..., return_mesh=True)``).

    Examples
    --------
    >>> import numpy as np, core
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> noisy = sphere * rng.normal(1.0, 0.03, size=(500, 1))
    >>> _, report = core.smooth_point_cloud(noisy, return_mesh=True)
    >>> report.n_distinct, report.mesh.faces.shape[1], len(report.swaps)  # a swap pass between rounds
    (500, 3, 2)
    >>> bool(report.noise.sigma > 0), report.rounds * report.iterations_per_round > 0
    (True, True)
    """

    mesh: RFSMesh  # final RFS mesh, vertex indices of the input points (first copy of duplicates)
    n_distinct: int
    sdg_edges: int
    emst_cut: int  # EMST edges cut as gaps (see core.pointcloud.sdg)
    isolated: int  # distinct points without a face: they cannot move
    swaps: list = field(default_factory=list)  # swaps per pass (one between consecutive rounds)
    seconds: dict = field(default_factory=dict)
    noise: NoiseEstimate = None  # the noise / spacing estimate (noise.ratio) the amount was chosen from
    rounds: int = 0  # the amount of smoothing that ran: rounds x iterations_per_round HC steps ...
    iterations_per_round: int = 0
    alpha: float = 0.0  # ... with this pull to the originals
    automatic: tuple = ()  # which of "alpha", "iterations_per_round" were chosen automatically
    influence: np.ndarray = None  # per input point: share of each step's move after round 1 (local amount)


AUTO = "auto"


def _whole(value, name, low, auto=False):
    if auto and isinstance(value, str) and value == AUTO:
        return AUTO
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < low:
        either = f"'{AUTO}' or " if auto else ""
        raise ValueError(f"{name} must be {either}a whole number >= {low}, got {value!r}")
    return int(value)


def _alpha(value):
    if isinstance(value, str):
        if value == AUTO:
            return AUTO
        raise ValueError(f"alpha must be '{AUTO}' or a number between 0 and 1, got {value!r}")
    return check_unit_interval(value, "alpha")


def _positive(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a number > 0, got {value!r}")
    return float(value)


def smooth_point_cloud(
    points: ArrayLike,
    *,
    alpha: float | str = AUTO,
    beta: float = 0.55,
    rounds: int = 3,
    iterations_per_round: int | str = AUTO,
    fixed: ArrayLike | None = None,
    neighbours: int = 16,
    spacing_factor: float = 2.5,
    gap_factor: float = 3.0,
    min_quality: float = 0.3,
    swap: bool = True,
    local_amount: bool = True,
    progress: Callable[[int, int], bool | None] | None = None,
    return_mesh: bool = False,
) -> np.ndarray | tuple[np.ndarray, PointCloudReport]:
    """Smooth a bare point cloud with HC through its RFS mesh (paper section 7).

    Parameters
    ----------
    points : (n, 3) array_like of float32 or float64
        The points; never modified. The result has the same shape and dtype.
    alpha : float in [0, 1] or "auto", default "auto"
        HC's pull towards the original points (see Notes for ``"auto"``).
    beta : float in [0, 1], default 0.55
        HC's weight of a point's own difference. HC converges for alpha > 0 and beta > 0.5.
    rounds : int >= 0, default 3
        How many times to run ``iterations_per_round`` HC steps, with a pass of edge swapping in
        between.
    iterations_per_round : int >= 1 or "auto", default "auto"
        HC steps per round (see Notes for ``"auto"``).
    fixed : (n,) bool mask or array_like of point indices, optional
        Points that never move.
    neighbours : int >= 2, default 16
        Size of the nearest-neighbour lists the SDG chooses from.
    spacing_factor, gap_factor : float > 0, default 2.5 and 3.0
        The SDG rule (see core.pointcloud.sdg); ``spacing_factor`` must not exceed ``gap_factor``.
    min_quality : float in [0, 1], default 0.3
        Bank & Smith threshold for RFS faces.
    swap : bool, default True
        Swap edges between rounds; False keeps the first RFS mesh.
    local_amount : bool, default True
        With the automatic amount (``iterations_per_round="auto"``), from the second round on each
        point takes a share of every step's move that follows its curvature against the noise
        (core.pointcloud.local_amount): thin parts and sharp rims get fewer effective steps than
        flat parts. False, or explicit steps: every point takes every step in full.
    progress : callable, optional
        ``progress(done, total)`` is called after each round; returning False raises `Cancelled`.
    return_mesh : bool, default False
        Also return a `PointCloudReport` holding the final RFS mesh, the noise estimate and the
        amount of smoothing that ran.

    Returns
    -------
    ndarray, or (ndarray, PointCloudReport) with ``return_mesh``
        The moved points, same shape and dtype as ``points``.

    Raises
    ------
    ValueError
        Bad arguments, or coordinates whose largest magnitude lies outside what the dtype holds at
        full precision (float64: about 2.2e-308 to 1.1e307), before any work.
    DivergenceError
        The run blew up (only possible outside HC's convergence region).
    Cancelled
        ``progress`` returned False.

    Notes
    -----
    The amount of smoothing follows the data: with the defaults ``iterations_per_round="auto"`` and
    ``alpha="auto"`` the noise is estimated relative to the sample spacing, r = sigma / h, and the
    total HC steps (spread over the rounds) and alpha follow from r by the rule of
    core.pointcloud.noise (``total_steps``, ``matched_alpha``): more steps and a weaker pull for
    heavier noise, a few steps with a strong pull for nearly clean, sparse samples. A number for
    either option is used as given (``iterations_per_round`` alone: alpha matched to the total steps;
    ``alpha`` alone: the steps still follow the noise), e.g. ``iterations_per_round=22, alpha=0.01``
    for 66 steps over the default 3 rounds. beta 0.55 and neighbours up to 2.5 local spacings were
    chosen with bench/bench_points.py (bench/results/2026-11-23-point-clouds.md at commit 555017f), as was swapping
    between rounds rather than after every step as in the paper (nearly the same result for a
    fraction of the swapping).

    The input is never modified. Exact duplicates move together; points the RFS mesh leaves without
    a face (isolated or unusable neighbourhoods) stay where they are.
    The unit does not matter: smoothing s * points gives s times the result (to rounding; bit for bit
    when s is a power of two). Coordinates whose largest magnitude lies outside what the dtype holds
    at full precision (float64: about 2.2e-308 to 1.1e307) raise ValueError before any work.

    Examples
    --------
    >>> import numpy as np, core
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> noisy = sphere * rng.normal(1.0, 0.03, size=(500, 1))  # radial noise
    >>> smoothed, report = core.smooth_point_cloud(noisy, return_mesh=True)
    >>> def spread(points):
    ...     return float(np.linalg.norm(points, axis=1).std())
    >>> bool(spread(smoothed) < spread(noisy) / 1.5), smoothed.shape == noisy.shape
    (True, True)
    >>> report.rounds, report.automatic
    (3, ('alpha', 'iterations_per_round'))

    The automatic amount for a noise of 0.1 and of 0.82 sample spacings:

    >>> from core.pointcloud import noise
    >>> [(noise.total_steps(r), round(noise.matched_alpha(noise.total_steps(r)), 4)) for r in (0.1, 0.82)]
    [(3, 0.22), (198, 0.0033)]
    """
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable progress(done, total) or None")
    run = PointCloudSmoother(
        points,
        alpha=alpha,
        beta=beta,
        rounds=rounds,
        iterations_per_round=iterations_per_round,
        fixed=fixed,
        neighbours=neighbours,
        spacing_factor=spacing_factor,
        gap_factor=gap_factor,
        min_quality=min_quality,
        swap=swap,
        local_amount=local_amount,
    )
    for _ in run.steps():
        if run.stage == "round" and progress is not None and progress(run.rounds_done, run.rounds) is False:
            raise Cancelled(f"cancelled after {run.rounds_done} of {run.rounds} rounds")
    return (run.result, run.report) if return_mesh else run.result


class PointCloudSmoother:
    """smooth_point_cloud in steps, for callers that interleave it with other work (a modal operator
    that shows progress and lets Esc cancel): checks everything on construction, then ``steps()``
    yields the fraction of the run done after each stage and round, as core.Smoothing.steps does
    (``stage`` names the last stage finished, None before the first, ``rounds_done`` counts the
    rounds), and on large clouds also between slices of a stage (core.pointcloud.stepwise: about a
    second of work each at a million points); once the generator is exhausted ``result`` and
    ``report`` are set. ``alpha`` and ``iterations_per_round`` hold
    "auto" until the first stage has estimated the noise, then the values in use. Abandoning the
    generator leaves the input untouched.

    Parameters are those of ``smooth_point_cloud`` without ``progress`` and ``return_mesh``.

    Examples
    --------
    >>> import numpy as np, core
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> noisy = sphere * rng.normal(1.0, 0.03, size=(500, 1))
    >>> run = core.pointcloud.PointCloudSmoother(noisy)
    >>> stages = [(run.stage, round(fraction, 2)) for fraction in run.steps()]
    >>> stages[:4]
    [('neighbours', 0.14), ('emst', 0.29), ('sdg', 0.43), ('rfs', 0.57)]
    >>> stages[-1], run.rounds_done
    (('round', 1.0), 3)
    >>> bool(np.array_equal(run.result, core.smooth_point_cloud(noisy)))
    True
    """

    def __init__(
        self,
        points,
        *,
        alpha=AUTO,
        beta=0.55,
        rounds=3,
        iterations_per_round=AUTO,
        fixed=None,
        neighbours=16,
        spacing_factor=2.5,
        gap_factor=3.0,
        min_quality=0.3,
        swap=True,
        local_amount=True,
    ):
        self.points = check_positions(points, "points")
        # Everything runs on points / scale (|coordinates| below 1): a power of two, so the division is
        # exact, a power-of-two change of unit changes no bit, and no squared distance over- or underflows.
        self.scale = power_of_two_scale(self.points, "points")
        # "auto" until the noise estimate (after the "neighbours" stage) replaces it with a number.
        self.alpha = _alpha(alpha)
        self.beta = check_unit_interval(beta, "beta")
        self.rounds = _whole(rounds, "rounds", 0)
        self.iterations_per_round = _whole(iterations_per_round, "iterations_per_round", 1, auto=True)
        self.automatic = tuple(name for name in ("alpha", "iterations_per_round") if getattr(self, name) == AUTO)
        self.noise = None
        self.neighbours = _whole(neighbours, "neighbours", 2)
        self.spacing_factor = _positive(spacing_factor, "spacing_factor")
        self.gap_factor = _positive(gap_factor, "gap_factor")
        problem = reach_gap_problem(self.spacing_factor, self.gap_factor)
        if problem:
            raise ValueError(problem)
        self.min_quality = check_unit_interval(min_quality, "min_quality")
        self.fixed = check_fixed(fixed, self.points.shape[0])
        self.swap = bool(swap)
        self.local_amount = bool(local_amount)
        self.result = None
        self.report = None
        self.stage, self.rounds_done = None, 0  # nothing finished yet

    BUILD_STAGES = ("neighbours", "emst", "sdg", "rfs")

    def _finished(self, stage, rounds_done=0):
        """Record a finished stage; the fraction of the run done (each stage and round counts one)."""
        self.stage, self.rounds_done = stage, rounds_done
        done = len(self.BUILD_STAGES) if stage == "round" else self.BUILD_STAGES.index(stage) + 1
        self.fraction = (done + rounds_done) / (len(self.BUILD_STAGES) + self.rounds)
        return self.fraction

    def _stage(self, stage, inner, rounds_done=0):
        """Run the stepwise generator ``inner`` (core.pointcloud.stepwise), yielding the run's
        fraction between its slices; then finish ``stage`` (``rounds_done`` for a round) and yield.
        Returns ``inner``'s result."""
        start, width = self.fraction, 1.0 / (len(self.BUILD_STAGES) + self.rounds)
        while True:
            try:
                part = next(inner)
            except StopIteration as stop:
                result = stop.value
                break
            yield start + width * part
        if stage in ("emst", "rfs"):  # the others time their parts themselves
            self._lap(stage)
        yield self._finished(stage, rounds_done)
        return result

    def _lap(self, name):
        now = time.perf_counter()
        self.seconds[name] = self.seconds.get(name, 0.0) + now - self._clock
        self._clock = now

    def steps(self):
        """The run in slices (yielding the fraction done); what a slice frees, the next reuses
        (core.memory.reusing)."""
        return reusing(self._steps())

    def _steps(self):
        self.seconds, self._clock, self.fraction = {}, time.perf_counter(), 0.0
        index = yield from self._stage("neighbours", self._neighbours())
        tree, _ = yield from self._stage("emst", emst_steps(index))
        graph = surface_description_graph(index, tree, spacing_factor=self.spacing_factor, gap_factor=self.gap_factor)
        self._lap("sdg")
        yield self._finished("sdg")
        mesh = yield from self._stage("rfs", rfs_steps(index.points, graph.edges, min_quality=self.min_quality))
        current = index.points  # a float64 copy, ours to move
        m = index.n_points
        swapper = EdgeSwapper(mesh.faces, m, mesh.other, mesh.edges) if self.swap and self.rounds > 1 else None
        # HC runs in the input's precision, as on meshes (float32 halves its memory traffic); the mesh's
        # geometry (swapping, curvature) stays in float64, which holds every float32 value exactly.
        precision = np.float32 if self.points.dtype == np.float32 else np.float64
        rounds = _Rounds(self, index, index.points.astype(precision, copy=False), swapper)
        for done in range(1, self.rounds + 1):
            current, mesh = yield from self._stage("round", rounds.run(done, current, mesh), done)
        self._finish(index, graph, mesh, current, rounds)

    def _neighbours(self):
        """The neighbour index, the fixed rows and the noise estimate with the amount it picks."""
        index = yield from NeighbourIndex.in_steps(self.points, self.neighbours, scale=self.scale)
        self.rows_fixed = np.zeros(index.n_points, dtype=bool)
        np.logical_or.at(self.rows_fixed, index.representative, self.fixed)  # a fixed copy pins its duplicates
        self._lap("neighbours")
        noise = estimate_noise(index)  # a fixed-size sample: the same small cost at any size
        self.noise_in_rows = noise
        self.noise = replace(noise, sigma=noise.sigma * self.scale, spacing=noise.spacing * self.scale)
        if self.iterations_per_round == AUTO:
            self.iterations_per_round = steps_per_round(self.noise.ratio, self.rounds)
        if self.alpha == AUTO:
            self.alpha = matched_alpha(self.rounds * self.iterations_per_round)
        self._lap("noise")
        return index

    def _finish(self, index, graph, mesh, current, rounds):
        """Set ``result`` and ``report``."""
        start, m = self.points, index.n_points
        result = (current[index.representative] * self.scale).astype(start.dtype)
        # Fixed and unmoved points bit-identical to the input, whatever the round trip did.
        still = self.fixed | ~np.any(current != index.points, axis=1)[index.representative]
        result[still] = start[still]
        has_face = np.zeros(m, dtype=bool)
        has_face[mesh.faces.ravel()] = True
        self.report = PointCloudReport(
            mesh=RFSMesh(index.original[mesh.faces], index.original[mesh.edges]),
            n_distinct=m,
            sdg_edges=int(graph.edges.shape[0]),
            emst_cut=graph.emst_cut,
            isolated=int(m - has_face.sum()),
            swaps=rounds.swaps,
            seconds=self.seconds,
            noise=self.noise,
            rounds=self.rounds,
            iterations_per_round=self.iterations_per_round,
            alpha=self.alpha,
            automatic=self.automatic,
            influence=None if rounds.influence is None else rounds.influence[index.representative],
        )
        self.result = result


# Non-zeros of the umbrella operator x HC steps per slice of a round (each step reads the operator
# twice): about a second of steps at a million points, a whole round on small clouds.
_HC_SLICE = 1 << 27


class _Rounds:
    """The rounds of a PointCloudSmoother run: HC steps, the local amount after the first, and a
    swap pass between consecutive rounds."""

    def __init__(self, smoother, index, original, swapper):
        self.smoother, self.index, self.original, self.swapper = smoother, index, original, swapper
        self.operator = None
        self.influence = None
        self.swaps = []

    def run_hc(self, current):
        """``iterations_per_round`` HC steps from ``current``, yielding between slices of steps."""
        run = self.smoother
        if self.operator is None:
            self.operator = umbrella_operator(self.mesh.edges, self.index.n_points)
        hc = Smoothing(
            current.astype(self.original.dtype, copy=False),
            None,
            method="hc",
            alpha=run.alpha,
            beta=run.beta,
            iterations=run.iterations_per_round,
            fixed=run.rows_fixed,
            original=self.original,
            operator=self.operator,
            influence=self.influence,
            stacklevel=6,
        )
        chunk = max(1, _HC_SLICE // max(int(self.operator.indptr[-1]), 1))
        while not hc.finished:
            hc.advance(chunk)
            if not hc.finished:
                yield hc.done / hc.iterations
        return hc.result().positions.astype(np.float64, copy=False)

    def run(self, done, current, mesh):
        """Round ``done`` (1, 2, ...) from ``current`` on ``mesh``; returns the positions and the mesh."""
        run, index = self.smoother, self.index
        self.mesh = mesh
        current = yield from self.run_hc(current)
        run._lap("hc")
        local = run.local_amount and "iterations_per_round" in run.automatic and index.k >= 5
        if local and done == 1 and run.rounds > 1:
            # Measured on the first round's result, where the noise no longer hides the curvature.
            noise = run.noise_in_rows
            self.influence = local_influence(
                sampled_curvature(current, index.neighbour, thinning(noise.ratio)),
                run.rounds * run.iterations_per_round,
                noise.sigma,
                noise.spacing,
            )
            run._lap("local amount")
        if self.swapper is not None and done < run.rounds:
            count = self.swapper.swap_pass(current)
            self.swaps.append(count)
            if count:
                self.mesh = RFSMesh(self.swapper.faces.copy(), self.swapper.edges)
                self.operator = None  # the neighbourhoods changed
            run._lap("swap")
        return current, self.mesh
