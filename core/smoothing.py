"""The smoothers of the paper: Laplacian (3.1), with the central point (3.2), with the original point (3.3),
and the HC algorithm (section 4, Algorithm 1), each simultaneous (Jacobi) or sequential (Gauss–Seidel).

Notation as in the paper: o original points, q current points (start of an iteration), p new points.
Every iteration is a few sparse products over all vertices at once; fixed vertices (and vertices
without neighbours, section 2) are copied through unchanged, so they stay bit-identical.

``Smoothing`` declares and checks every argument; ``smooth`` runs it to the end, and ``hc_smooth`` and
``laplacian_smooth`` are ``smooth`` with the method fixed. The arguments they share are described
once, in argument_docs, and put into each docstring.
"""

import math
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TypedDict, Unpack

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from . import locality, parallel
from .adjacency import Umbrella, umbrella_operator
from .argument_docs import documented
from .convergence import ConvergenceWarning, DivergenceError, convergence_message, divergence_message
from .geometry import project_within
from .triangular import triangular_solver
from .validation import (
    bbox_diagonal,
    check_choice,
    check_fixed,
    check_influence,
    check_iterations,
    check_max_deviation,
    check_positions,
    check_tolerance,
    check_unit_interval,
    squares_are_safe,
)

METHODS = ("hc", "plain", "central", "original")
MODES = ("simultaneous", "sequential")
# The defaults: inside HC's convergence region (Theorem 5.2: alpha > 0, beta > 0.5), so a run at them
# settles on a shape of the input's size; the paper's recommended pairing, and the add-on's defaults.
DEFAULT_ALPHA = 0.1
DEFAULT_BETA = 0.6


class Cancelled(Exception):
    """Raised when a progress callback returns False; the input positions are untouched.

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> try:
    ...     core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=10, progress=lambda done, total: done < 3)
    ... except core.Cancelled as stop:
    ...     print(stop)
    cancelled after 3 of 10 iterations
    """


@dataclass(frozen=True)
class SmoothResult:
    """What ``smooth`` and ``Smoothing.result`` return.

    Attributes
    ----------
    positions : ndarray
        The smoothed positions, same shape and dtype as the input.
    iterations : int
        Iterations actually run.
    stopped_early : bool
        The tolerance was reached before ``iterations``.

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> result = core.smooth(positions, edges, alpha=0.1, beta=0.6, iterations=1000, tolerance=1e-6)
    >>> result.positions.shape, result.iterations, bool(result.stopped_early)
    ((4, 3), 10, True)
    """

    positions: np.ndarray
    iterations: int
    stopped_early: bool


class SmoothingOptions(TypedDict, total=False):
    """The types of what ``Smoothing`` takes besides the arrays, the method and its numbers, for the
    ``**options`` that ``smooth`` passes on to it (described in ``Smoothing``'s docstring)."""

    mode: str
    fixed: ArrayLike | None
    tolerance: float
    original: ArrayLike | None
    operator: Umbrella | None
    influence: ArrayLike | None
    max_deviation: float


class SmoothOptions(SmoothingOptions, total=False):
    """``SmoothingOptions`` and ``smooth``'s progress callback: what ``hc_smooth`` and
    ``laplacian_smooth`` pass on to ``smooth``."""

    progress: Callable[[int, int], bool | None] | None


def _check_names(options, accepted, function):
    """Raise the TypeError Python raises for a keyword argument that ``function`` does not take: its
    ``**options`` accept the names of the TypedDict ``accepted``."""
    for name in options:
        if name not in accepted.__optional_keys__:
            raise TypeError(f"{function}() got an unexpected keyword argument {name!r}")


@documented
def smooth(
    positions: ArrayLike,
    edges: ArrayLike | None,
    *,
    method: str = "hc",
    alpha: float = DEFAULT_ALPHA,
    beta: float = DEFAULT_BETA,
    iterations: int,
    progress: Callable[[int, int], bool | None] | None = None,
    **options: Unpack[SmoothingOptions],
) -> SmoothResult:
    """Run one of the smoothers to the end and say how many iterations ran.

    The common entry point of ``hc_smooth`` and ``laplacian_smooth``: ``Smoothing`` run at once.

    Parameters
    ----------
    {arrays}
    {numbers}
    {progress}

    Other Parameters
    ----------------
    {options}

    Returns
    -------
    SmoothResult
        The new positions, the iterations that ran and whether the tolerance stopped the run.

    Raises
    ------
    {raises}
    Cancelled
        ``progress`` returned False.

    Warns
    -----
    ConvergenceWarning
        HC outside the region where it is proven to converge (alpha > 0 and beta > 0.5).

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> result = core.smooth(positions, edges, method="central", alpha=0.5, iterations=1)
    >>> result.positions.round(3).tolist()
    [[0.167, 0.167, 0.167], [0.5, 0.167, 0.167], [0.167, 0.5, 0.167], [0.167, 0.167, 0.5]]
    >>> result.iterations, bool(result.stopped_early)
    (1, False)
    """
    _check_names(options, SmoothingOptions, "smooth")
    run = Smoothing(
        positions,
        edges,
        method=method,
        alpha=alpha,
        beta=beta,
        iterations=iterations,
        stacklevel=4,
        **options,
    )
    if progress is None:
        run.advance()
    else:
        while not run.finished:
            run.advance(1, check=False)
            if progress(run.done, run.iterations) is False:
                raise Cancelled(f"cancelled after {run.done} of {run.iterations} iterations")
    return run.result()


# A result whose bounding box is this many times the input's has blown up: smoothing moves points
# towards their neighbours, and inside the convergence region never comes close to this.
BLOW_UP_FACTOR = 10.0


@documented
class Smoothing:
    """One smoothing run, advanced in slices.

    Every argument is checked on construction. ``advance(k)`` runs up to k more iterations and
    ``result()`` hands the positions back; ``smooth`` is ``advance()`` once. A caller that shows
    progress advances in chunks and gets the same result bit for bit (the tolerance is measured
    against the input's bounding box whatever the chunk).

    Parameters
    ----------
    {arrays}
    {numbers}
    {options}
    stacklevel : int, default 2
        Where a `ConvergenceWarning` points, as in `warnings.warn` (2: the caller).

    Attributes
    ----------
    iterations : int
        The most iterations the run does (0 when no vertex can move).
    done : int
        Iterations run so far.
    stopped_early : bool
        The tolerance stopped the run.
    finished : bool
        Nothing is left to run.

    Raises
    ------
    {raises}

    Warns
    -----
    ConvergenceWarning
        HC outside the region where it is proven to converge (alpha > 0 and beta > 0.5).

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> run = core.Smoothing(positions, edges, alpha=0.1, beta=0.6, iterations=10)
    >>> run.advance(4), run.done, run.finished
    (4, 4, False)
    >>> [round(fraction, 1) for fraction in run.steps(chunk=3)]
    [0.7, 1.0]
    >>> result = run.result()
    >>> at_once = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=10)
    >>> result.iterations, bool(np.array_equal(result.positions, at_once))
    (10, True)
    """

    def __init__(
        self,
        positions: ArrayLike,
        edges: ArrayLike | None,
        *,
        method: str = "hc",
        alpha: float = DEFAULT_ALPHA,
        beta: float = DEFAULT_BETA,
        iterations: int,
        mode: str = "simultaneous",
        fixed: ArrayLike | None = None,
        tolerance: float = 0.0,
        original: ArrayLike | None = None,
        operator: Umbrella | None = None,
        influence: ArrayLike | None = None,
        max_deviation: float = 0.0,
        stacklevel: int = 2,
    ) -> None:
        self.method = method = check_choice(method, "method", METHODS)
        mode = check_choice(mode, "mode", MODES)
        self.alpha = check_unit_interval(alpha, "alpha")
        self.beta = check_unit_interval(beta, "beta")
        self.iterations = check_iterations(iterations)
        tolerance = check_tolerance(tolerance)
        start = check_positions(positions)
        max_deviation = check_max_deviation(max_deviation, start.shape[0])
        n = start.shape[0]
        origin = start if original is None or original is positions else _checked_original(original, start)
        operator = _checked_operator(operator, edges, n)
        fixed_mask = check_fixed(fixed, n) | operator.isolated
        weights = check_influence(influence, n)
        if method == "hc" and self.iterations > 0:
            message = convergence_message(self.alpha, self.beta)
            if message:
                warnings.warn(message, ConvergenceWarning, stacklevel=stacklevel)

        self.shape, self.dtype = start.shape, start.dtype
        self.threshold = tolerance * bbox_diagonal(start) if tolerance > 0.0 else 0.0
        self.plain_squares = squares_are_safe(self.threshold, start.dtype) and squares_are_safe(
            bbox_diagonal(start), start.dtype
        )
        # What "blown up" is measured against: the box around the input and the originals.
        self.reference_box = _box(start) if origin is start else _box(np.concatenate([start, origin]))
        renumbered = locality.renumbering(operator) if mode == "simultaneous" and self.iterations > 0 else None
        self.order = renumbered.order if renumbered is not None else None
        if renumbered is not None:  # scattered vertex order: work in a cache-friendly one
            operator, fixed_mask = renumbered.operator, fixed_mask[self.order]
            weights = weights[self.order] if weights is not None else None
        # Vertices of partial influence take that fraction of each iteration's move (1: the full step). They
        # stay in the paper's V_var: the weight scales the move, not the neighbours' differences b.
        influence_moves = _Influence.of(weights, fixed_mask, start.dtype)
        # The iterations work on planar copies, one contiguous row per coordinate (see core.parallel).
        self.current = _planar(start, self.order)
        per_vertex = isinstance(max_deviation, np.ndarray)  # then 0 keeps a vertex where it is
        limited = (per_vertex or max_deviation > 0.0) and self.iterations > 0
        if isinstance(max_deviation, np.ndarray) and self.order is not None:
            max_deviation = max_deviation[self.order]
        limit = _Limit(self.current.copy(), max_deviation) if limited else None
        self.step = _step_for(
            operator,
            fixed_mask,
            self.current if origin is start else _planar(origin, self.order),
            method,
            mode,
            self.alpha,
            self.beta,
            start.dtype,
            influence_moves,
            limit,
        )  # (keeps α o, never o itself)
        # A step that writes into ``spare`` swaps it with ``current`` every iteration.
        self.spare = np.empty_like(self.current) if self.step.writes_out else None
        self.done = 0
        self.stopped_early = False
        self.checked = True
        if not self.step.movable.any():
            self.iterations = 0  # nothing can move: every iteration would return its input

    @property
    def finished(self):
        return self.stopped_early or self.done >= self.iterations

    def steps(self, chunk: int | None = None) -> Iterator[float]:
        """Advance ``chunk`` iterations at a time (all at once if None), yielding the fraction of the run
        done after each slice, as core.pointcloud.PointCloudSmoother.steps does; then call ``result()``."""
        while not self.finished:
            self.advance(chunk)
            yield 1.0 if self.finished else self.done / self.iterations
        if not self.done:
            yield 1.0  # nothing to run: one slice, already done

    def advance(self, count: int | None = None, check: bool = True) -> int:
        """Run up to ``count`` more iterations (all that remain if None); returns how many ran.
        ``check``: raise DivergenceError now if the positions have blown up (else ``result()`` does)."""
        count = self.iterations - self.done if count is None else min(count, self.iterations - self.done)
        ran = 0
        with np.errstate(over="ignore", invalid="ignore"):  # a run that blows up is refused by _check
            while ran < count and not self.stopped_early:
                new = self.step(self.current, self.spare)
                if self.threshold > 0.0:
                    move = new - self.current
                    if not self.plain_squares:  # extreme scales: measure moves in thresholds
                        move /= move.dtype.type(self.threshold)
                    largest = np.sqrt(np.max(np.einsum("ij,ij->j", move, move)))
                    self.stopped_early = largest < (self.threshold if self.plain_squares else 1.0)
                if self.spare is not None:
                    self.spare = self.current
                self.current = new
                ran += 1
        self.done += ran
        self.checked = self.checked and not ran
        if check:
            self._check()
        return ran

    def result(self) -> SmoothResult:
        """The positions in the input's shape, dtype and vertex order, as a SmoothResult."""
        self._check()
        if self.finished:  # the step's buffers go before the result is made
            self.step = self.spare = None
        positions = np.empty(self.shape, dtype=self.dtype)
        if self.order is None:
            positions[...] = self.current.T
        else:
            positions[self.order] = self.current.T
        return SmoothResult(positions, self.done, self.stopped_early)

    def _check(self):
        if self.checked:
            return
        low, high = self.reference_box
        new_low, new_high = self.current.min(axis=1), self.current.max(axis=1)
        size = math.hypot(*(high - low))
        grown = np.maximum(high, new_high) - np.minimum(low, new_low)
        if not np.all(np.isfinite(grown)):
            what = "coordinates became infinite or NaN"
        elif math.hypot(*grown) > BLOW_UP_FACTOR * size:
            what = f"the bounding box grew {math.hypot(*grown) / size:.3g} times"
        else:
            self.checked = True
            return
        raise DivergenceError(divergence_message(self.method, self.alpha, self.beta, self.done, what))


class _Influence:
    """Painted influence: a vertex of weight w in (0, 1) ends an iteration at q + w (p - q) instead of p.
    Applied to rows in place while they are in cache (a chunk of a simultaneous pass, or all rows);
    weight 0 keeps q itself (bit-identical, even -0.0), not q + 0."""

    def __init__(self, weight, partial, zero):
        self.weight, self.partial, self.zero = weight, partial, zero

    @classmethod
    def of(cls, weights, fixed_mask, dtype):
        """None when every movable vertex takes the full step."""
        if weights is None:
            return None
        scaled = (weights < 1.0) & ~fixed_mask
        if not scaled.any():
            return None
        zero = scaled & (weights == 0.0)
        return cls(np.where(scaled, weights, 1.0).astype(dtype), scaled & ~zero, zero if zero.any() else None)

    def apply(self, p, q, rows=slice(None)):
        """p[:, rows] (planar, written in place) becomes q + w (p - q) on the weighted rows."""
        p_rows, q_rows = p[:, rows], q[:, rows]
        blended = np.subtract(p_rows, q_rows)
        blended *= self.weight[rows]
        blended += q_rows
        np.copyto(p_rows, blended, where=self.partial[rows])
        if self.zero is not None:
            np.copyto(p_rows, q_rows, where=self.zero[rows])


class _Limit:
    """The deviation limit: a vertex ends every iteration at most ``radius`` from its input position (a
    projection onto the ball around it). Applied to rows in place while they are in cache, after the
    influence; fixed vertices never leave their position, so it never touches them."""

    def __init__(self, start, radius):
        self.start = start  # planar (3, n), in the run's vertex order
        self.radius = radius  # a distance, or one per vertex (in the run's vertex order)
        self.squared = radius * radius

    def apply(self, p, rows=slice(None)):
        squared = self.squared[rows] if isinstance(self.radius, np.ndarray) else self.squared
        radius = self.radius[rows] if isinstance(self.radius, np.ndarray) else self.radius
        project_within(p[:, rows], self.start[:, rows], radius, squared)


def _checked_original(original, start):
    """The paper's original points o as an array of ``start``'s shape and dtype, or ValueError."""
    origin = check_positions(original, "original")
    if origin.shape != start.shape:
        raise ValueError(f"original must have the shape of positions {start.shape}, got {origin.shape}")
    return origin.astype(start.dtype, copy=False)


def _checked_operator(operator, edges, n):
    """The umbrella to smooth with: ``operator`` if it is one for ``n`` vertices (else ValueError), or one
    built from ``edges``."""
    if operator is None:
        return umbrella_operator(edges, n)
    if not isinstance(operator, Umbrella) or operator.n_vertices != n:
        raise ValueError(f"operator must be a core.umbrella_operator built for {n} vertices")
    return operator


def _box(points):
    """(low, high) corners of the bounding box of (n, 3) points, in float64."""
    if points.shape[0] == 0:
        return np.zeros(3), np.zeros(3)
    return (
        np.array([points[:, k].min() for k in range(3)], dtype=np.float64),
        np.array([points[:, k].max() for k in range(3)], dtype=np.float64),
    )


def _planar(points, order=None):
    """A (3, n) C-contiguous copy of (n, 3) ``points`` (rows taken in ``order`` if given). Always a
    copy: for Fortran-ordered input ``points.T`` is already contiguous, and the steps write into it."""
    if order is None:
        return np.array(points.T, order="C")
    return np.take(points.T, order, axis=1)


@documented
def hc_smooth(
    positions: ArrayLike,
    edges: ArrayLike | None,
    *,
    alpha: float,
    beta: float,
    iterations: int,
    **options: Unpack[SmoothOptions],
) -> np.ndarray:
    """Smooth a mesh with the HC algorithm (paper section 4, Algorithm 1).

    Each iteration moves every vertex to the mean of its neighbours (p), then pushes it back by
    its own and its neighbours' differences b = p - (alpha o + (1 - alpha) q). ``smooth`` with
    ``method="hc"``.

    Parameters
    ----------
    {arrays}
    alpha : float in [0, 1]
        Pull towards the original points o.
    beta : float in [0, 1]
        Weight of a vertex's own difference b_i against its neighbours' mean difference.
    iterations : int >= 0
        How many iterations to run.

    {wrapper}

    Warns
    -----
    ConvergenceWarning
        alpha = 0 or beta <= 0.5: HC is proven to converge only for alpha > 0 and beta > 0.5
        (Theorem 5.2); it runs, but many iterations may drift.

    See Also
    --------
    laplacian_smooth : the Laplacian variants, which shrink.
    smooth_mesh : the pipeline the operators run (chooses the amount, keeps the volume).

    Examples
    --------
    A noisy 5 x 5 plate: HC takes the noise out and keeps the plate's width, plain Laplacian
    smoothing shrinks it.

    >>> import numpy as np, core
    >>> u, v = np.meshgrid(range(5), range(5))
    >>> edges = [(i, i + 1) for i in range(25) if i % 5 < 4] + [(i, i + 5) for i in range(20)]
    >>> noisy = np.c_[u.ravel(), v.ravel(), np.random.default_rng(0).normal(scale=0.1, size=25)]
    >>> smoothed = core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=10)
    >>> plain = core.laplacian_smooth(noisy, edges, iterations=10)
    >>> [round(float(np.ptp(p[:, 0])), 2) for p in (noisy, smoothed, plain)]  # width
    [4.0, 3.67, 0.94]
    >>> bool(np.abs(smoothed[:, 2]).max() < np.abs(noisy[:, 2]).max())
    True
    >>> border = [0, 1, 2, 3, 4]
    >>> pinned = core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=10, fixed=border)
    >>> bool(np.array_equal(pinned[border], noisy[border]))
    True
    """
    _check_names(options, SmoothOptions, "hc_smooth")
    return smooth(positions, edges, method="hc", alpha=alpha, beta=beta, iterations=iterations, **options).positions


@documented
def laplacian_smooth(
    positions: ArrayLike,
    edges: ArrayLike | None,
    *,
    variant: str = "plain",
    alpha: float = 0.0,
    iterations: int,
    **options: Unpack[SmoothOptions],
) -> np.ndarray:
    """Smooth a mesh with a Laplacian variant of the paper's section 3.

    Each iteration moves every vertex towards the mean m_i of its neighbours: to m_i (``"plain"``,
    3.1), to alpha q_i + (1 - alpha) m_i (``"central"``, 3.2) or to alpha o_i + (1 - alpha) m_i
    (``"original"``, 3.3). ``smooth`` with ``method=variant``.

    Parameters
    ----------
    {arrays}
    variant : {"plain", "central", "original"}, default "plain"
        Which Laplacian.
    alpha : float in [0, 1], default 0.0
        Weight of the current point q_i (``"central"``) or of the original point o_i
        (``"original"``); ``"plain"`` does not use it.
    iterations : int >= 0
        How many iterations to run.

    {wrapper}

    See Also
    --------
    hc_smooth : HC, which takes noise out without the shrinking.

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> core.laplacian_smooth(positions, edges, iterations=1).round(3).tolist()
    [[0.333, 0.333, 0.333], [0.0, 0.333, 0.333], [0.333, 0.0, 0.333], [0.333, 0.333, 0.0]]
    >>> core.laplacian_smooth(positions, edges, iterations=1, fixed=[0]).round(3).tolist()[0]
    [0.0, 0.0, 0.0]
    >>> core.laplacian_smooth(positions, edges, variant="central", alpha=0.5, iterations=1).round(3).tolist()[1]
    [0.5, 0.167, 0.167]
    """
    _check_names(options, SmoothOptions, "laplacian_smooth")
    variant = check_choice(variant, "variant", METHODS[1:])
    return smooth(positions, edges, method=variant, alpha=alpha, iterations=iterations, **options).positions


class _Step:
    """One iteration q -> p of the chosen smoother, with everything reusable prepared once.

    ``step(q, out)`` returns the new positions, written into ``out`` when ``writes_out``; ``q`` is kept.
    """

    writes_out = False

    def __init__(self, fixed_mask, origin, method, alpha, beta, influence, limit):
        self.influence = influence  # an _Influence or None
        self.limit = limit  # a _Limit or None
        self.movable = ~fixed_mask
        self.fixed_index = np.flatnonzero(fixed_mask)
        self.method, self.alpha, self.beta = method, alpha, beta
        # Weight of the neighbour average in the Laplacian pass (HC's pass is the plain one).
        self.neighbour_weight = 1.0 - alpha if method in ("central", "original") else 1.0
        self.alpha_origin = alpha * origin if method in ("hc", "original") and alpha > 0.0 else None


def _copy_rows(destination, source, index):
    """destination[:, index] = source[:, index] for planar arrays, one coordinate row at a time (a
    1-D take/put is several times faster than fancy indexing on the second axis)."""
    if index.size:
        for to, of in zip(destination, source):
            np.put(to, index, np.take(of, index))


def _zero_rows(array, index):
    if index.size:
        for row in array:
            row[index] = 0.0


def _step_for(operator, fixed_mask, origin, method, mode, alpha, beta, dtype, influence, limit):
    kind = _SequentialStep if mode == "sequential" else _SimultaneousStep
    return kind(operator, fixed_mask, origin, method, alpha, beta, dtype, influence, limit)


class _SimultaneousStep(_Step):
    """Every pass of an iteration runs on row blocks, one per thread (core.parallel)."""

    writes_out = True

    def __init__(self, operator, fixed_mask, origin, method, alpha, beta, dtype, influence, limit):
        super().__init__(fixed_mask, origin, method, alpha, beta, influence, limit)
        dtype = np.dtype(dtype)
        self.blocks = parallel.RowBlocks(operator.indptr, operator.indices, operator.n_vertices)
        # Each block resets its own fixed rows.
        bounds = np.searchsorted(
            self.fixed_index, [block.rows.start for block in self.blocks.blocks] + [operator.n_vertices]
        )
        self.block_fixed = {
            id(block): self.fixed_index[bounds[k] : bounds[k + 1]] for k, block in enumerate(self.blocks.blocks)
        }
        # T x = (sum of x over adj(i)) / |adj(i)|: the products sum over the pattern, and each row's
        # factor (with the step's constants folded in) is applied to the sums while they are in cache.
        inverse_degree = np.zeros(operator.n_vertices, dtype=dtype)
        np.divide(1.0, operator.degree, out=inverse_degree, where=operator.degree > 0)
        if method == "hc":
            self.mean_factor = inverse_degree  # T
            self.scaled_factor = inverse_degree * dtype.type(1.0 - beta)  # (1-β) T
        else:
            self.scaled_factor = inverse_degree * dtype.type(self.neighbour_weight)  # w T
        self.scratch = None  # d of HC, allocated on the first step

    def __call__(self, q, out):
        if self.method == "hc":
            self._hc_step(q, out)
        else:
            self._laplacian_step(q, out)
        return out

    def _laplacian_step(self, q, p):
        """p_i = a s_i + w/|adj(i)| Σ_j q_j on movable rows, with a s_i = α q_i (central), α o_i (original)."""

        def combine(rows, sums):
            sums *= self.scaled_factor[rows]
            if self.method == "central":
                sums += np.multiply(q[:, rows], self.alpha)
            elif self.alpha_origin is not None:
                sums += self.alpha_origin[:, rows]
            p[:, rows] = sums
            if self.influence is not None:
                self.influence.apply(p, q, rows)
            if self.limit is not None:
                self.limit.apply(p, rows)

        def block_step(block):
            block.neighbour_sums(q, combine)
            _copy_rows(p, q, self.block_fixed[id(block)])

        self.blocks.run(block_step)

    def _hc_step(self, q, p):
        """Algorithm 1 of the paper, in two passes over row blocks. The paper, per vertex i in V_var:

            p_i = (1/|adj(i)|) Σ_{j∈adj(i)} q_j                    (Laplacian pass)
            b_i = p_i - (α o_i + (1-α) q_i)
            p_i = p_i - (β b_i + (1-β)/|adj(i)| Σ_{j∈adj(i)} b_j)   (correction pass)

        In matrix form with s = α o + (1-α) q: b = T q - s and p = T q - β b - (1-β) T b. As T q = b + s,
        p = s + w - T w with w = (1-β) b: the first pass makes s and w (one product, T q), the second
        adds w - T w (one product, T w). w is 0 on fixed vertices (not in V_var) and p = q there.
        tests/core/paper_reference.py runs the per-vertex form; the two agree to rounding.
        """
        if self.scratch is None:
            self.scratch = np.empty_like(q)
        w = self.scratch
        keep = 1.0 - self.beta

        def first(rows, sums):  # sums = Σ_j q_j. p = s, w = (1-β)(T q - s)
            s = np.multiply(q[:, rows], 1.0 - self.alpha, out=p[:, rows])
            if self.alpha_origin is not None:
                s += self.alpha_origin[:, rows]
            w_rows = np.multiply(s, -keep, out=w[:, rows])
            sums *= self.scaled_factor[rows]  # (1-β)/|adj(i)|
            w_rows += sums

        def second(rows, sums):  # sums = Σ_j w_j. p = s + w - T w
            p_rows = p[:, rows]
            p_rows += w[:, rows]
            sums *= self.mean_factor[rows]  # 1/|adj(i)|
            p_rows -= sums
            if self.influence is not None:
                self.influence.apply(p, q, rows)
            if self.limit is not None:
                self.limit.apply(p, rows)

        def first_pass(block):
            block.neighbour_sums(q, first)
            _zero_rows(w, self.block_fixed[id(block)])

        def second_pass(block):
            block.neighbour_sums(w, second)
            _copy_rows(p, q, self.block_fixed[id(block)])

        self.blocks.run(first_pass)
        self.blocks.run(second_pass)


class _SequentialStep(_Step):
    """Gauss–Seidel Laplacian pass (a triangular solve), then (HC) the correction with b built from
    the new points. The solve makes its own arrays, so ``out`` is not used.

    The coordinates are independent, so the passes around the solve run one task per coordinate, on
    threads; the solve itself takes all coordinates in one call (see core.triangular).
    """

    def __init__(self, operator, fixed_mask, origin, method, alpha, beta, dtype, influence, limit):
        super().__init__(fixed_mask, origin, method, alpha, beta, influence, limit)
        self.gauss_seidel = _GaussSeidel(operator, self.movable, self.neighbour_weight, dtype)

    def __call__(self, q, out=None):
        anchor = None  # a s_i: α q_i (central) or α o_i (original)
        if self.method == "central" and self.alpha > 0.0:
            anchor = self.alpha * q
        elif self.method == "original":
            anchor = self.alpha_origin
        p = self.gauss_seidel.solve(q, anchor)  # fixed rows of the system read p_i = q_i exactly
        if self.method == "hc":
            self.gauss_seidel.each_coordinate(lambda k: self._correct(q[k], p[k], k), len(p))
        if self.influence is not None:
            self.influence.apply(p, q)
        if self.limit is not None:
            self.limit.apply(p)
        return p

    def _correct(self, q, p, k):
        """HC's correction of one coordinate row, in place in ``p``."""
        fixed = self.fixed_index
        # b_i = p_i - (α o_i + (1-α) q_i); zero on fixed vertices, which are not in V_var.
        b = np.multiply(q, 1.0 - self.alpha)
        np.subtract(p, b, out=b)
        if self.alpha_origin is not None:
            b -= self.alpha_origin[k]
        if fixed.size:
            b[fixed] = 0.0
        # p_i -= β b_i + (1-β)/|adj(i)| Σ_j b_j (T from its two triangles: T itself is never built)
        neighbour_mean = self.gauss_seidel.neighbour_mean(b)
        neighbour_mean *= 1.0 - self.beta
        p -= neighbour_mean
        b *= self.beta
        p -= b
        if fixed.size:
            np.put(p, fixed, np.take(q, fixed))


class _GaussSeidel:
    """The sequential Laplacian pass as one sparse triangular solve.

    For movable i: p_i - w Σ_{j<i} t_ij p_j = w Σ_{j>i} t_ij q_j + a s_i, i.e. (I - w L) p = w U q + a s,
    with L, U the strictly lower/upper parts of T restricted to movable rows; fixed rows read p_i = q_i.
    (A fixed neighbour j < i has p_j = q_j, so it may sit on either side.) U is read from the rows of
    the pattern, L from its columns: a directed pattern (core.adjacency) works as a symmetric one does.
    """

    def __init__(self, operator, movable, weight, dtype):
        n = operator.n_vertices
        lower_indptr, lower_indices = operator.lower_columns
        counts = np.diff(lower_indptr)
        # w t_ij on movable rows, 0 on fixed ones: row i of U and of L.
        row_weight = np.zeros(n, dtype=dtype)
        scale = movable & (operator.degree > 0)
        row_weight[scale] = weight / operator.degree[scale]
        self.row_weight = row_weight
        # U x as row_weight * (sums over the upper pattern); one block, as the tasks here are per coordinate.
        self.upper_rows = parallel.RowBlocks(operator.upper_indptr, operator.upper_indices, n, workers=1).blocks[0]
        # I - w L in CSC: column j is the diagonal 1, then -w t_ij for the vertices i > j with j in adj(i)
        # (the lower pattern's column j), already in increasing row order.
        indptr = np.zeros(n + 1, dtype=lower_indptr.dtype)
        np.cumsum(counts + 1, out=indptr[1:])
        off_diagonal = np.ones(indptr[-1], dtype=bool)
        off_diagonal[indptr[:-1]] = False
        indices = np.empty(indptr[-1], dtype=lower_indices.dtype)
        indices[indptr[:-1]] = np.arange(n)
        indices[off_diagonal] = lower_indices
        data = np.ones(indptr[-1], dtype=dtype)
        data[off_diagonal] = -row_weight[lower_indices]
        self.system = sp.csc_matrix((data, indices, indptr), shape=(n, n))
        self.solve_lower = triangular_solver(self.system)
        self.fixed_index = np.flatnonzero(~movable)
        self.weight = weight
        self.threaded = indptr[-1] >= parallel.MIN_WORK and parallel.thread_count() > 1

    def each_coordinate(self, task, count):
        """task(k) for every coordinate row k, one thread each on big meshes (the rows share nothing).
        Three equal tasks on two cores finish sooner as three threads than as two plus one."""
        if self.threaded and count > 1:
            parallel.run_all([lambda k=k: task(k) for k in range(count)])
        else:
            for k in range(count):
                task(k)

    def neighbour_mean(self, x):
        """T x for one coordinate row x on movable rows (fixed rows: anything; callers overwrite them),
        from the two triangles: L x = x - (I - L) x holds for the weight 1 of the HC Laplacian pass only."""
        if self.weight != 1.0:
            raise AssertionError("neighbour_mean needs the system of a weight-1 (plain or HC) Laplacian pass")
        result = self.system @ x
        np.subtract(x, result, out=result)  # L x

        def add_upper(rows, sums):  # + U x
            sums *= self.row_weight[rows]
            result[rows] += sums[0]

        self.upper_rows.neighbour_sums(x, add_upper)
        return result

    def solve(self, q, anchor):
        rhs = np.empty_like(q)

        def right_hand_side(k):  # w U q + a s on movable rows, q on fixed ones
            def combine(rows, sums):  # the chunks cover every row, so every row is written
                np.multiply(sums[0], self.row_weight[rows], out=rhs[k, rows])
                if anchor is not None:
                    rhs[k, rows] += anchor[k, rows]

            self.upper_rows.neighbour_sums(q[k], combine)
            if self.fixed_index.size:
                np.put(rhs[k], self.fixed_index, np.take(q[k], self.fixed_index))

        self.each_coordinate(right_hand_side, len(q))
        return self.solve_lower(rhs)
