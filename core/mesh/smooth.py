"""The mesh pipeline: choose the amount, smooth, give closed parts their volume back.

``smooth_mesh`` is the mesh twin of ``smooth_point_cloud``, and ``MeshSmoother`` runs it in slices for
callers that show progress and let the user cancel (the operators, the command line). Every route that
smooths a mesh (operators, command line, demo, benchmarks, examples) goes through here, so they all
run the same numbers.

Numbers a caller gives are used exactly. The Automatic Amount (HC only) chooses what is left at
``"auto"``: with ``iterations="auto"`` and ``alpha="auto"`` it chooses the iterations from the mesh's
own noise (core.mesh.amount) with alpha 0, holding parts without noise, gives every closed part
its volume back within bounds (core.mesh.volume), and gives a part whose shape it changed its input back
(core.mesh.collapse); with ``beta="auto"`` it may take gentler steps on light noise. Either number given
switches it off: the other then takes its default (``DEFAULT_ALPHA``, ``DEFAULT_ITERATIONS``) and the run
is the paper's algorithm, bit for bit what ``core.hc_smooth`` gives.

``keep_in_place`` (core.mesh.in_place) keeps only the part of each vertex's move across the surface, along its
normal: textures, UVs and open outlines stay where they were. ``"auto"`` (the default) turns it on with
the Automatic Amount and off when numbers are given, so that given numbers run the paper's algorithm.

Two options change the mesh the run sees, both off by default: ``weld`` runs coincident vertices as
one (core.mesh.welding), ``border`` chooses what open borders do (core.mesh.borders). ``keep_sharp_edges`` (off by
default) smooths with core.mesh.sharp_edges instead of HC's umbrella: the creases of hard-surface parts stay.
"""

import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import locality, parallel
from ..adjacency import Umbrella, umbrella_operator
from ..convergence import ConvergenceWarning
from ..geometry import fan_triangles, median_edge_length, project_rows_within
from ..memory import reusing
from ..slices import as_fraction, to_end
from ..smoothing import DEFAULT_ALPHA, DEFAULT_BETA, METHODS, MODES, Cancelled, Smoothing
from ..validation import (
    check_choice,
    check_fixed,
    check_influence,
    check_iterations,
    check_max_deviation,
    check_positions,
    check_tolerance,
    check_unit_interval,
)
from . import collapse, sharp_amount, sharp_edges, topology, volume, welding
from .amount import PATCH_FROM, AmountChooser, MeshAmount
from .borders import BORDERS, apply_border, border_edges
from .in_place import Outline, curve_labels, inward_directions, keep_in_place_steps, outline_curves
from .noise import noise_steps, read_on_every_vertex_steps
from .sharp_edges import DEFAULT_SHARPNESS_ANGLE, SharpSmoothing, check_sharpness_angle, check_triangles

AUTO = "auto"
DEFAULT_ITERATIONS = 10
# The Automatic Amount's deviation limit, in estimated noise (standard deviations along the normals): the
# farthest a vertex may move when the caller set no limit.
DEVIATION_IN_NOISE = 4.0
# Of a run with the Automatic Amount, the part of its progress the choice takes: its runs (the data and
# the probes) go about twice as far as the smoothing that follows; on big meshes they go on patches
# (core.mesh.amount), which cost a few iterations of the whole mesh.
CHOOSING_SHARE = 2 / 3
PATCH_CHOOSING_SHARE = 1 / 5
RESTORE_SHARE = 1 / 10  # ... and the volume restore, at the end


@dataclass(frozen=True)
class MeshReport:
    """What a mesh run did.

    Attributes
    ----------
    method, alpha, beta : the smoother and the numbers it ran with (chosen or given).
    iterations : int
        Iterations run (fewer than asked when the tolerance stopped the run early).
    amount : MeshAmount or None
        What the Automatic Amount chose and the noise it estimated; None when the numbers were given.
    volume_offset : float
        The largest uniform offset along the normals that gave a closed part its volume back (0: none).
    max_deviation : float
        The deviation limit the run kept to (0: none).
    seconds : float
        Wall time of the whole run.
    keep_sharp_edges : bool
        The run smoothed with core.mesh.sharp_edges (then ``iterations`` counts its steps, alpha and beta are
        its push-back's weights, and ``sharpness_angle`` the angle it kept).
    sharpness_angle : float or None
        Radians; None when ``keep_sharp_edges`` is off.
    held_parts : int
        Parts whose shape the Automatic Amount would have changed (collapsed, or smoothed away with the
        noise), given their input positions back (core.mesh.collapse).
    kept_in_place : bool
        Each vertex's move was kept to its part across the surface (core.mesh.in_place).
    choosing_seconds, finishing_seconds : float
        Of ``seconds``: what went before the iterations (welding, the noise test, the Automatic Amount's
        choice; on meshes below core.mesh.amount.PATCH_FROM the choice runs the chosen iterations itself)
        and what came after them (Keep in Place, the volume restore, the parts given back).

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> _, report = core.smooth_mesh(positions, edges, iterations=5, return_report=True)
    >>> report.method, report.alpha, report.beta, report.iterations, report.amount
    ('hc', 0.1, 0.6, 5, None)
    """

    method: str
    alpha: float
    beta: float
    iterations: int
    amount: MeshAmount | None
    volume_offset: float
    max_deviation: float
    seconds: float
    keep_sharp_edges: bool = False
    sharpness_angle: float | None = None
    held_parts: int = 0
    kept_in_place: bool = False
    choosing_seconds: float = 0.0
    finishing_seconds: float = 0.0


def _auto_or(value, name):
    """``value`` if it is a number (checked later, with the rest), AUTO if it says so."""
    if isinstance(value, str):
        if value == AUTO:
            return AUTO
        raise ValueError(f"{name} must be '{AUTO}' or a number, got {value!r}")
    return value


class MeshSmoother:
    """``smooth_mesh`` in slices: everything is checked on construction; ``steps()`` yields the fraction
    of the run done after each slice, as core.Smoothing.steps does; once it is exhausted ``result`` and
    ``report`` are set. Abandoning the generator cancels: the input is never modified.

    Parameters are those of ``smooth_mesh``; ``operator`` is a prebuilt ``umbrella_operator`` (then
    ``edges`` is not read).

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> run = core.MeshSmoother(positions, edges, alpha=0.1, beta=0.6, iterations=3)
    >>> fractions = list(run.steps(chunk=1))
    >>> [round(f, 2) for f in fractions]
    [0.33, 0.67, 1.0]
    >>> run.report.iterations
    3
    """

    def __init__(
        self,
        positions: ArrayLike,
        edges: ArrayLike | None = None,
        *,
        faces: ArrayLike | None = None,
        method: str = "hc",
        alpha: float | str = AUTO,
        beta: float | str = AUTO,
        iterations: int | str = AUTO,
        mode: str = "simultaneous",
        tolerance: float = 0.0,
        fixed: ArrayLike | None = None,
        influence: ArrayLike | None = None,
        max_deviation: float | str = AUTO,
        operator: Umbrella | None = None,
        weld: bool = False,
        border: str = "free",
        keep_sharp_edges: bool = False,
        sharpness_angle: float = DEFAULT_SHARPNESS_ANGLE,
        keep_in_place: bool | str = AUTO,
        work_budget: float | None = None,
        hold_parts: bool = True,
    ) -> None:
        self.positions = start = check_positions(positions)
        n = start.shape[0]
        self.method = check_choice(method, "method", METHODS)
        if not isinstance(keep_sharp_edges, (bool, np.bool_)):
            raise ValueError(f"keep_sharp_edges must be True or False, got {keep_sharp_edges!r}")
        self.keep_sharp_edges = bool(keep_sharp_edges)
        self.sharpness_angle = check_sharpness_angle(sharpness_angle)
        alpha, beta, iterations = _auto_or(alpha, "alpha"), _auto_or(beta, "beta"), _auto_or(iterations, "iterations")
        hc = self.method == "hc" or self.keep_sharp_edges  # Keep Sharp Edges replaces the method's umbrella
        self.automatic = hc and alpha == AUTO and iterations == AUTO
        self.beta_given = beta != AUTO
        if self.keep_sharp_edges:
            self.alpha = sharp_edges.DEFAULT_ALPHA if alpha == AUTO else alpha
            self.beta = sharp_edges.DEFAULT_BETA if beta == AUTO else beta
            self.iterations = sharp_edges.DEFAULT_ITERATIONS if iterations == AUTO else iterations
        else:
            self.alpha = DEFAULT_ALPHA if alpha == AUTO else alpha
            self.beta = DEFAULT_BETA if beta == AUTO else beta
            self.iterations = DEFAULT_ITERATIONS if iterations == AUTO else iterations
        self.max_deviation = _auto_or(max_deviation, "max_deviation")
        if isinstance(self.max_deviation, np.ndarray):
            raise ValueError(
                "max_deviation must be one distance >= 0 (0 for no limit) or 'auto' (core.smooth takes one per vertex)"
            )
        self.mode = mode
        self.tolerance = tolerance
        if operator is None:
            operator = umbrella_operator(edges, n)
        elif not isinstance(operator, Umbrella) or operator.n_vertices != n:
            raise ValueError(f"operator must be a core.umbrella_operator built for {n} vertices")
        self.fixed = check_fixed(fixed, n)
        self.influence = check_influence(influence, n)
        self.faces = None if faces is None else fan_triangles(faces)
        if self.keep_sharp_edges:
            check_triangles(self.faces, n)  # no faces: a clear ValueError now, not after the welding
        self.in_place = self._in_place(keep_in_place)
        self.border = check_choice(border, "border", BORDERS)
        if self.border != "free" and self.faces is None:
            raise ValueError(
                f"border={border!r} needs the faces (a border edge is an edge of exactly one face): pass faces=, "
                "or border='free'"
            )
        self.operator, self.weld = operator, bool(weld)
        self.work_budget, self.hold_parts = work_budget, bool(hold_parts)
        # Every number checked now, as core.Smoothing checks them.
        check_choice(mode, "mode", MODES)
        self.alpha = check_unit_interval(self.alpha, "alpha")  # float: a Fraction reports as the number ran
        self.beta = check_unit_interval(self.beta, "beta")
        self.iterations = check_iterations(self.iterations)
        self.tolerance = check_tolerance(tolerance)
        check_max_deviation(0.0 if self.max_deviation == AUTO else self.max_deviation, n)
        self.welding = self.surface = self.renumbering = None
        self.kept = 0.0  # the chosen HC run's t = tr(S) / n (core.mesh.amount), where the Automatic Amount ran
        self.prepared = False  # the welding, the faces' surface and the border rule: the first slices of steps()
        self.result = None
        self.report = None

    def _in_place(self, keep_in_place):
        """Whether the run keeps vertices in place: AUTO is on with the Automatic Amount (HC's) where
        faces are given."""
        if _auto_or(keep_in_place, "keep_in_place") == AUTO:
            return self.automatic and not self.keep_sharp_edges and self.faces is not None
        if not isinstance(keep_in_place, (bool, np.bool_)):
            raise ValueError(f"keep_in_place must be True, False or '{AUTO}', got {keep_in_place!r}")
        if keep_in_place and self.faces is None:
            raise ValueError("keep_in_place=True needs the faces (the vertex normals come from them): pass faces=")
        return bool(keep_in_place)

    def _prepare(self):
        """Weld coincident vertices (core.mesh.welding: the result is scattered back), renumber a scattered
        mesh (core.locality: the result is put back in the caller's order), find what the faces make (parts,
        closed ones, border edges: for the border rule and the volume restore) and apply the border rule,
        yielding 0.0 between these passes."""
        operator = self.operator
        surfaced = self.faces is not None and (self.border != "free" or self.automatic)
        if self.weld or surfaced:
            yield 0.0  # the construction built the operator: a slice of its own before these passes
        if self.weld:
            self.welding = yield from as_fraction(welding.weld_steps(self.positions, operator), 0.0)
            if self.welding is not None:
                self.positions, operator = self.welding.positions(), self.welding.operator(operator)
                self.fixed, self.influence = self.welding.fixed(self.fixed), self.welding.influence(self.influence)
                if self.faces is not None:
                    self.faces = self.welding.triangles(self.faces)
            yield 0.0
        if self.mode == "simultaneous" and (self.automatic or self.iterations > 0):
            # A scattered numbering: every pass reads neighbours close by (core.locality).
            self.renumbering = locality.renumbering(operator)
            if self.renumbering is not None:
                yield 0.0  # the order took a slice (about 0.3 s a million vertices): the mapping takes another
                renumbering = self.renumbering
                self.positions, operator = renumbering.rows(self.positions), renumbering.operator
                self.fixed, self.influence = renumbering.rows(self.fixed), renumbering.rows(self.influence)
                if self.faces is not None:  # a plain run with numbers given reads no faces
                    reads = self.automatic or self.in_place or self.keep_sharp_edges or self.border != "free"
                    self.faces = renumbering.triangles(self.faces) if reads else None
                yield 0.0
        if surfaced:
            self.surface = yield from as_fraction(topology.surface_steps(self.faces, operator.n_vertices), 0.0)
            yield 0.0
        edges = None if self.surface is None else self.surface.border
        # The Automatic Amount chooses on the surface's own umbrella: its noise test and GCV read a
        # vertex's 1-ring, which a border vertex's curve row is not.
        self.surface_operator = operator
        self.operator, self.fixed = apply_border(self.border, operator, self.faces, self.fixed, edges)
        self.prepared = True

    def still(self) -> np.ndarray:
        """(n,) bool: the vertices this run never moves (fixed, held by the border rule, without
        neighbours), in the caller's numbering."""
        if not self.prepared:
            to_end(self._prepare())
        still = self.fixed | self.operator.isolated
        if self.renumbering is not None:
            still = self.renumbering.scatter(still)
        return still if self.welding is None else still[self.welding.label]

    def _smoothing(self, alpha, beta, iterations, max_deviation, fixed=None):
        with warnings.catch_warnings():  # callers report the convergence region themselves
            warnings.simplefilter("ignore", ConvergenceWarning)
            return Smoothing(
                self.positions,
                None,
                method=self.method,
                alpha=alpha,
                beta=beta,
                iterations=iterations,
                mode=self.mode,
                tolerance=self.tolerance,
                fixed=self.fixed if fixed is None else fixed,
                influence=self.influence,
                max_deviation=max_deviation,
                operator=self.operator,
            )

    def steps(self, chunk: int | None = None) -> Iterator[float]:
        """Run in slices of ``chunk`` iterations (all at once if None), yielding the fraction done; the
        Automatic Amount's choice and volume restore yield between their passes too. With Keep Sharp Edges,
        what a slice frees the next reuses (core.memory.reusing: its passes make fresh arrays of the mesh's
        size; HC's iterations keep theirs, and gain nothing from it but a larger heap)."""
        return reusing(self._steps(chunk)) if self.keep_sharp_edges else self._steps(chunk)

    def _steps(self, chunk):
        start = time.perf_counter()
        if not self.prepared:
            yield from self._prepare()
        if self.keep_sharp_edges:
            yield from self._sharp_steps(chunk, start)
            return
        alpha, beta, iterations, amount, done, noise = self.alpha, self.beta, self.iterations, None, None, None
        limit = 0.0 if self.max_deviation == AUTO else self.max_deviation
        fixed, share, restoring = self.fixed, 0.0, self.automatic and self.faces is not None
        if restoring:  # what the restore needs of the input, on another thread while the choice runs on one
            measuring = parallel.in_background(lambda: volume.measure_before(self.positions, self.faces, self.surface))
        if self.automatic:
            chooser = AmountChooser(
                self.positions,
                operator=self.surface_operator,
                beta=self.beta,
                fixed=self.fixed,
                work_budget=self.work_budget,
            )
            if self.beta_given:
                chooser.fine_beta = None  # the caller's beta is used as given
            share = CHOOSING_SHARE if self.operator.n_vertices < PATCH_FROM else PATCH_CHOOSING_SHARE
            for fraction in chooser.steps():
                if fraction < 1.0:
                    yield share * fraction
            amount, fixed = chooser.amount, chooser.fixed  # the Automatic Amount holds parts without noise
            self.kept = chooser.kept  # t at the amount chosen: what core.mesh.collapse's move rule reads
            noise = chooser.noise
            alpha, beta, iterations = amount.alpha, amount.beta, amount.iterations
            if self.max_deviation == AUTO:
                limit = self._noise_limit(noise, amount.sigma)
            unlimited = not isinstance(limit, np.ndarray) and not limit
            same = self.operator is self.surface_operator
            if same and self.influence is None and self.mode == "simultaneous" and not self.tolerance and unlimited:
                done = chooser.result()  # the choice ran exactly these iterations on its way: not again
            del chooser  # its runs' buffers go before the smoothing's come
        end = 1.0 - RESTORE_SHARE if restoring else 1.0  # where the smoothing's share of the progress ends
        chosen = time.perf_counter()
        if done is not None:
            result, ran = done, iterations
        else:
            smoothing = self._smoothing(alpha, beta, iterations, limit, fixed)
            for fraction in smoothing.steps(chunk):
                if fraction < 1.0:
                    yield share + (end - share) * fraction
            smoothed = smoothing.result()
            del smoothing
            result, ran = smoothed.positions, smoothed.iterations
        measured = measuring if restoring else None
        run, smoothed_at = (alpha, beta, ran), time.perf_counter()
        offset, held = yield from self._finish(result, run, amount, fixed, limit, measured, end, noise, "correlation")
        largest = float(np.max(limit)) if np.size(limit) else 0.0
        now = time.perf_counter()
        self.report = MeshReport(
            self.method,
            alpha,
            beta,
            ran,
            amount,
            offset,
            largest,
            now - start,
            False,
            None,
            held,
            self.in_place,
            chosen - start,
            now - smoothed_at,
        )
        yield 1.0

    def _noise_limit(self, noise, sigma):
        """The Automatic Amount's deviation limit: DEVIATION_IN_NOISE times the noise, and on the parts
        core.mesh.noise limits (quiet ones, light noise) their own radius."""
        limit = DEVIATION_IN_NOISE * sigma
        if noise.limited.any():
            limit = np.where(noise.limited, noise.quiet_radius(self.positions, DEVIATION_IN_NOISE), limit)
        return limit

    def _finish(self, result, run, amount, fixed, limit, measuring, progress, noise=None, residual=None):
        """Keep each move across the surface (Keep in Place), give closed parts their volume back (when
        ``measuring`` holds the input's measure: the Automatic Amount) within the deviation limit, give the
        parts the run collapsed their input back (with the ``noise`` core.mesh.noise found: the Automatic
        Amount; core.mesh.collapse), and the parts whose shape it took away too, read from the residual as
        ``residual`` says ("correlation": HC's rules, "move": Keep Sharp Edges'), and set ``result`` in the
        caller's numbering; returns (the largest offset, the parts given back), yielding ``progress``
        between the restore's slices and the rules. With Keep in Place the parts are judged on the run's own
        moves, before they are kept across the surface (and before the volume restore); ``run``: the
        (alpha, beta, iterations) that ran, which smooth the open borders as curves for Keep in Place."""
        offset, parts, ran, normals = 0.0, None, run[2], None
        if self.in_place and ran > 0:
            if noise is not None and self.hold_parts:
                parts = yield from self._held_parts(result, noise, residual, progress)
            outline = self._outline(result, run, fixed, limit) if self.border == "free" else None
            keeping = keep_in_place_steps(self.positions, result, self.faces, outline, with_normals=True)
            result, normals = yield from as_fraction(keeping, progress)  # the volume's offsets go along them
            if outline is not None and np.any(limit):  # across the surface and the curve at once: both limited
                project_rows_within(result, self.positions, limit)
        if measuring is not None and ran > 0:
            limited = volume.NOISE_OFFSETS * amount.sigma
            result, offset = yield from self._keep_volume(result, fixed, limited, measuring.result(), progress, normals)
            if np.any(limit):  # the offset keeps to the limit too
                project_rows_within(result, self.positions, limit)
        if parts is None and noise is not None and ran > 0 and self.hold_parts:
            parts = yield from self._held_parts(result, noise, residual, progress)
        held = 0 if parts is None else int(np.count_nonzero(parts))
        if held:
            back = parts[noise.part_of_vertex]
            result[back] = self.positions[back]
        if self.renumbering is not None:
            result = self.renumbering.scatter(result)
        self.result = result if self.welding is None else self.welding.scatter(result)
        return offset, held

    def _outline(self, result, run, fixed, limit):
        """The open borders smoothed as curves (core.mesh.in_place.Outline) with the run's (alpha, beta,
        iterations), fixed vertices, influence and limit: the same smoother on the border edges alone, a
        vertex where more or fewer than two meet held; the side the surface lies on read on the run's
        ``result`` (smoothed: noise cannot turn it). None without such vertices."""
        n = self.operator.n_vertices
        edges = self.surface.border if self.surface is not None else border_edges(self.faces, n)
        vertices, before, after = outline_curves(edges, n)
        if vertices.size == 0:
            return None
        border = np.unique(edges)
        held = fixed[border] | ~np.isin(border, vertices, assume_unique=True)
        alpha, beta, iterations = run
        with warnings.catch_warnings():  # the run itself was judged against the convergence region
            warnings.simplefilter("ignore", ConvergenceWarning)
            curves = Smoothing(
                self.positions[border],
                np.searchsorted(border, edges),
                method=self.method,
                alpha=alpha,
                beta=beta,
                iterations=iterations,
                mode=self.mode,
                fixed=held,
                influence=None if self.influence is None else self.influence[border],
                max_deviation=limit[border] if isinstance(limit, np.ndarray) else limit,
            )
            to_end(curves.steps())
        inward = inward_directions(result, self.surface_operator, vertices)
        loop = curve_labels(edges, vertices)
        return Outline(vertices, before, after, inward, loop, border, curves.result().positions)

    def _held_parts(self, result, noise, residual, progress):
        """(parts,) bool: the parts core.mesh.collapse gives their input back: collapsed, moved by more than
        their noise, or (``residual`` "correlation": HC's) their shape taken away with the noise, as the
        residual's neighbour correlation reads it; yields ``progress`` between the rules."""
        parts = collapse.collapsed(self.positions, result, noise.part_of_vertex, noise.sigma)
        yield progress  # a second or so each on millions of vertices: a cancel waits for one at most
        if residual == "correlation" and self.faces is not None:
            parts |= collapse.smooth_residual(
                self.positions, result, self.faces, self.surface_operator, noise.part_of_vertex, parts.size
            )
        if self.faces is not None:
            asked, kept = noise.noisy, 0.0
            if residual == "correlation":  # HC: as its correlation rule, big scans are not asked (a pass of normals)
                asked = np.bincount(noise.part_of_vertex, minlength=parts.size) < collapse.PATCH_FROM
                # the trace's bound on light-noise and quiet parts (core.mesh.collapse), where the estimate holds
                kept = np.where(noise.light | ~noise.noisy, self.kept, 0.0)
            sigma = noise.sigma if noise.floor is None else noise.floor

            def moved(sigma, asked):
                return collapse.moved_beyond_noise(
                    self.positions, result, self.faces, noise.part_of_vertex, sigma, asked, kept, residual == "move"
                )

            beyond = moved(sigma, asked)
            again = beyond & noise.sampled  # an estimate read on a share of the part: all of it asked first
            if again.any():
                yield progress
                reading = read_on_every_vertex_steps(noise, self.positions, self.surface_operator, again)
                beyond &= ~again | moved((yield from as_fraction(reading, progress)), again)
            parts |= beyond
        return parts

    def _sharp_steps(self, chunk, start):
        """``steps`` with Keep Sharp Edges (core.mesh.sharp_edges): with the Automatic Amount the steps, and an
        angle no narrower than the noise's, come from the noise core.mesh.noise finds (parts without noise
        held or kept within a small radius, as HC's default does), and closed parts get their volume back.
        Where it finds noise the filter is guided, steps set or not (a clean coarse model keeps Sun et al.'s)."""
        iterations, amount, fixed, angle, noise = self.iterations, None, self.fixed, self.sharpness_angle, None
        guided = False  # the guidance where core.mesh.noise finds noise (core.mesh.sharp_edges), steps set or not
        limit = 0.0 if self.max_deviation == AUTO else self.max_deviation
        restoring, share = self.automatic and self.faces is not None, 0.0
        if restoring:
            measuring = parallel.in_background(lambda: volume.measure_before(self.positions, self.faces, self.surface))
        if self.automatic:
            share = sharp_amount.CHOOSING_SHARE
            noise = yield from as_fraction(noise_steps(self.positions, self.surface_operator), 0.0)
            edge = median_edge_length(self.positions, self.surface_operator)
            sigma = noise.level()
            ratio = sigma / edge if edge > 0 else 0.0
            if not noise.found:  # light noise at most: smoothed within a small radius (below)
                ratio = min(ratio, sharp_amount.QUIET_RATIO)
            guided = noise.found
            iterations = sharp_amount.steps_for_noise(ratio, self.faces.shape[0])
            angle = sharp_amount.angle_for_noise(angle, ratio)
            fixed = fixed | noise.held()
            if fixed.all():  # nothing to smooth (clean parts only)
                iterations = 0
            amount = MeshAmount(self.alpha, self.beta, iterations, sigma, edge, 0, noise.found)
            if self.max_deviation == AUTO:
                limit = self._noise_limit(noise, sigma)
            yield share
        elif self.iterations > 0:  # set steps: the noise test only chooses the filter
            share = sharp_amount.CHOOSING_SHARE
            guided = (yield from as_fraction(noise_steps(self.positions, self.surface_operator), 0.0)).found
            yield share
        end = 1.0 - RESTORE_SHARE if restoring else 1.0
        chosen = time.perf_counter()
        run = SharpSmoothing(
            self.positions,
            self.faces,
            sharpness_angle=angle,
            iterations=iterations,
            alpha=self.alpha,
            beta=self.beta,
            fixed=fixed,
            influence=self.influence,
            max_deviation=limit,
            tolerance=self.tolerance,
            operator=self.operator,
            guided=guided,
        )
        for fraction in run.steps(chunk):
            if fraction < 1.0:
                yield share + (end - share) * fraction
        result, ran = run.result(), run.done
        del run
        measured = measuring if restoring else None
        run, smoothed_at = (self.alpha, self.beta, ran), time.perf_counter()
        offset, held = yield from self._finish(result, run, amount, fixed, limit, measured, end, noise, "move")
        largest = float(np.max(limit)) if np.size(limit) else 0.0
        now = time.perf_counter()
        self.report = MeshReport(
            *(self.method, self.alpha, self.beta, ran, amount, offset, largest, now - start, True, angle, held),
            *(self.in_place, chosen - start, now - smoothed_at),
        )
        yield 1.0

    def _keep_volume(self, result, fixed, limit, measured, progress, normals=None):
        """Each closed part's volume given back by a bounded uniform offset of its moving vertices along
        their normals (core.mesh.volume; ``normals``: (3, n) the directions Keep in Place kept the moves
        along, else ``result``'s vertex normals), in slices (yielding ``progress``); returns (positions,
        largest offset). Fixed vertices and those of influence 0 stay bit for bit."""
        movable = ~fixed if self.influence is None else ~fixed & (self.influence > 0.0)
        restored, offsets = yield from as_fraction(
            volume.restore_steps(
                self.positions, result, self.faces, movable, limit, result.dtype, self.surface, measured, normals
            ),
            progress,
        )
        still = ~movable
        restored[still] = result[still]
        return restored, float(np.abs(offsets).max()) if offsets.size else 0.0

    def run(self, progress: Callable[[float], bool | None] | None = None) -> np.ndarray:
        """All slices; ``progress(fraction)`` after each, False cancels (raises core.Cancelled)."""
        for fraction in self.steps(None if progress is None else 1):
            if progress is not None and fraction < 1.0 and progress(fraction) is False:
                raise Cancelled(f"cancelled at {fraction:.0%}")
        return self.result


def smooth_mesh(
    positions: ArrayLike,
    edges: ArrayLike | None = None,
    *,
    return_report: bool = False,
    progress: Callable[[float], bool | None] | None = None,
    **options,
) -> np.ndarray | tuple[np.ndarray, MeshReport]:
    """Smooth a mesh as the HC Smooth operator does: the Automatic Amount unless numbers are given.

    Parameters
    ----------
    positions : (n, 3) float32 or float64 array
        Vertex positions; never modified. The result has the same shape and dtype.
    edges : (m, 2) integer array
        Vertex pairs, undirected; order, direction, duplicates and self-loops do not matter.
    faces : (f, k) integer array, or (offsets, corner_verts), optional
        The faces; needed to give closed parts their volume back (Automatic Amount).
    method : {"hc", "plain", "central", "original"}
        HC (paper section 4) or a Laplacian variant (3.1-3.3).
    alpha, beta : float or "auto"
        HC's weights (paper section 4). ``"auto"``: see below.
    iterations : int or "auto"
        How many iterations to run.
    mode : {"simultaneous", "sequential"}
        The paper's Algorithm 1, or Gauss-Seidel in increasing vertex order.
    tolerance : float
        Stop once the largest move of an iteration is below ``tolerance`` x the bounding-box diagonal.
    fixed : bool mask or vertex indices, optional
        Vertices that never move.
    influence : (n,) floats in [0, 1], optional
        Each vertex moves by this share of each iteration's move (0 stays bit-identical).
    max_deviation : float or "auto"
        The farthest any vertex may end from its input position, in the positions' units (every
        iteration ends with a projection onto that ball); 0: no limit. ``"auto"``: with the Automatic
        Amount ``DEVIATION_IN_NOISE`` times the noise it estimated, else no limit.
    weld : bool
        Smooth coincident vertices (equal, or within 1e-6 of the median edge length apart: UV seams,
        triangle soups, STL) as one vertex (core.mesh.welding): they move alike, a soup like its welded mesh.
        The result still has every vertex. A welded vertex is fixed if any of its copies is, and takes
        the least influence of its copies; the faces (and whether they are closed) are taken as welded.
    border : {"free", "curve", "fixed"}
        Open-border vertices (on an edge of one face) average all their neighbours (the paper's
        algorithm), follow their border as a curve, or stay (core.mesh.borders). "curve" and "fixed" need faces.
    keep_sharp_edges : bool
        Smooth with core.mesh.sharp_edges (face normals filtered without averaging across creases, vertices
        fitted to them, HC's push-back) instead of HC's umbrella: for hard-surface scans. Needs faces.
        ``iterations`` then counts its steps (default ``core.mesh.sharp_edges.DEFAULT_ITERATIONS``), alpha and
        beta weight its push-back (defaults 0 and ``core.mesh.sharp_edges.DEFAULT_BETA``); ``method`` and
        ``mode`` are not used. The Automatic Amount chooses the steps from the noise core.mesh.noise finds.
    sharpness_angle : float
        Radians in (0, pi): faces meeting at more than this angle keep their crease (as Blender's Auto
        Smooth angle). Default ``core.mesh.sharp_edges.DEFAULT_SHARPNESS_ANGLE``.
    keep_in_place : bool or "auto"
        Keep only the part of each vertex's move across the surface (along the result's vertex normal,
        core.mesh.in_place): textures, UVs and open outlines stay where they were. Needs faces. ``"auto"``: on
        with the Automatic Amount (HC's, where faces are given), off when numbers are given (the paper's
        algorithm, bit for bit).
    work_budget : float, optional
        The Automatic Amount's most vertex-iterations (None: ``core.mesh.amount.WORK_BUDGET``; ``math.inf``: no cut).
    hold_parts : bool
        The Automatic Amount gives parts whose shape the run took away their input back (core.mesh.collapse);
        False: never (for measuring what that rule holds).
    return_report : bool
        Also return a MeshReport (what ran, what was chosen).
    progress : callable, optional
        ``progress(fraction)`` after each iteration; False cancels (raises core.Cancelled).

    With ``alpha`` and ``iterations`` both ``"auto"`` (the default) and method HC, the Automatic Amount
    chooses the iterations from the mesh's own noise (none where it finds none: nothing moves), runs them
    with alpha 0 and gives each closed part its volume back; ``beta="auto"`` lets it take gentler steps
    on light noise. A number for either of ``alpha`` or ``iterations`` switches it off; the other then
    takes its default (0.1, 10).

    Examples
    --------
    >>> import numpy as np, core
    >>> rng = np.random.default_rng(0)
    >>> u, v = np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20))
    >>> flat = np.stack([u.ravel(), v.ravel(), np.zeros(400)], axis=1)
    >>> noisy = flat + [0, 0, 1] * rng.normal(scale=0.01, size=(400, 1))
    >>> grid = np.arange(400).reshape(20, 20)
    >>> edges = np.concatenate([np.stack([grid[:, :-1].ravel(), grid[:, 1:].ravel()], 1),
    ...                         np.stack([grid[:-1].ravel(), grid[1:].ravel()], 1)])
    >>> smoothed, report = core.smooth_mesh(noisy, edges, return_report=True)
    >>> bool(np.abs(smoothed[:, 2]).std() < np.abs(noisy[:, 2]).std())
    True
    >>> report.amount is not None, report.alpha
    (True, 0.0)
    >>> same = core.smooth_mesh(noisy, edges, alpha=0.1, beta=0.6, iterations=10)
    >>> bool(np.array_equal(same, core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=10)))
    True
    """
    run = MeshSmoother(positions, edges, **options)
    run.run(progress)
    return (run.result, run.report) if return_report else run.result
