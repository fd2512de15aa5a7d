"""One smoothing job per point cloud: its points, the core run through the RFS mesh (paper section 7,
core.smooth_point_cloud) and the report, as functions of a ``settings_spec.PointSettings``.

Without Blender: the point operator (operators/point_cloud.py) reads objects into clouds and writes their
results back; the command line's --points makes one of a scan file's points (cli/file_route.py).
"""

import warnings

import numpy as np

from .. import core, settings_spec
from ..core import MAX_POINT_CLOUD_STEPS, PointCloudSmoother, collinear, matched_alpha, reach_gap_problem
from . import InputError

# Reach and Gap as the panel names them, for the rule that ties them.
REACH_GAP = (settings_spec.SPACING_FACTOR.label, settings_spec.GAP_FACTOR.label)


def too_few_points(name, positions):
    """Why ``positions`` cannot be smoothed (fewer than three distinct points, or all on one line: no RFS
    face), or None."""
    n = len(positions)
    if n == 1:
        return f"'{name}' is a single point: nothing to smooth"
    differs = np.any(positions != positions[0], axis=1)
    if not differs.any():
        return f"All {n} points of '{name}' coincide: nothing to smooth"
    other = np.all(positions == positions[int(np.argmax(differs))], axis=1)
    if np.all(other | ~differs):  # every point is the first one or that other one
        return f"The {n} points of '{name}' lie at only 2 distinct positions: nothing to smooth"
    if collinear(positions):
        return f"The {n} points of '{name}' lie on one straight line: no RFS face can form, nothing to smooth"
    return None


class Cloud:
    """One point cloud to smooth: its points, those that stay fixed (a mask, or None), and after ``run`` its
    result and report. ``name`` is what messages call it. A Blender object's cloud also knows where its
    points go (operators/point_cloud.py); a file's has no object to write to."""

    obj = data = key_block = None

    def __init__(self, name, positions, fixed=None):
        if len(positions) == 0:
            raise InputError(f"'{name}' has no points: nothing to smooth")
        too_few = too_few_points(name, positions)
        if too_few:
            raise InputError(too_few)
        self.positions, self.fixed = positions, fixed
        self.result = self.report = None


def check_settings(settings):
    """Raise InputError for settings no cloud can run with (Reach and Gap that do not fit together)."""
    problem = reach_gap_problem(settings.spacing_factor, settings.gap_factor, REACH_GAP)
    if problem:
        raise InputError(problem)


def make_smoother(cloud, settings):
    """The core's stepwise run for one cloud; raises ValueError for settings the core refuses."""
    return PointCloudSmoother(
        cloud.positions,
        alpha="auto" if settings.auto_amount else settings.alpha,
        beta=settings.beta,
        rounds=settings.rounds,
        iterations_per_round="auto" if settings.auto_amount else settings.iterations_per_round,
        fixed=cloud.fixed,
        neighbours=settings.neighbours,
        spacing_factor=settings.spacing_factor,
        gap_factor=settings.gap_factor,
        min_quality=settings.min_quality,
        swap=settings.swap,
    )


def run(clouds, settings):
    """Every cloud's stages in turn; yields the fraction done and sets each cloud's result. Writes nothing."""
    for number, cloud in enumerate(clouds):
        smoother = make_smoother(cloud, settings)
        with warnings.catch_warnings():  # the convergence region is reported once, at the end
            warnings.simplefilter("ignore", core.ConvergenceWarning)
            for fraction in smoother.steps():
                yield (number + fraction) / len(clouds)
        cloud.result, cloud.report = smoother.result, smoother.report


def lowest_alpha(settings, given=()):
    """The smallest alpha a run with these settings (``given``: the names the caller set) can use, before it
    has estimated the noise."""
    # With the automatic amount, alpha is matched_alpha(steps) >= matched_alpha(MAX_POINT_CLOUD_STEPS) > 0:
    # only beta can leave the region.
    automatic = settings_spec.automatic(settings_spec.values_of(settings, settings_spec.POINTS), given)
    return matched_alpha(MAX_POINT_CLOUD_STEPS) if automatic else settings.alpha


def convergence_note(settings):
    """The convergence-region warning for these settings (before a run), or None."""
    return core.convergence_message(lowest_alpha(settings), settings.beta)


def amount(report):
    """What ran: '3 rounds of 15 steps'."""
    return f"{report.rounds} rounds of {report.iterations_per_round} steps"


def stuck_warning(clouds):
    """The warning for runs where most points found no RFS face (and so could not move), or None."""
    still = sum(c.report.isolated for c in clouds)
    distinct = sum(c.report.n_distinct for c in clouds)
    if still <= distinct / 2:
        return None
    counted = "points" if distinct == sum(len(c.positions) for c in clouds) else "distinct points"
    # Typically scan lines much farther apart than the points along them: the graph keeps to the
    # lines and no faces form, so the points cannot move.
    return (
        f"{still} of {distinct} {counted} have no RFS faces and did not move: the points are much farther "
        "apart in one direction (scan lines?). Raise Reach, Gap and Neighbours to connect them"
    )


def summary(clouds, settings):
    points = sum(len(c.positions) for c in clouds)
    seconds = sum(sum(c.report.seconds.values()) for c in clouds)
    still = sum(c.report.isolated for c in clouds)
    names = f"{len(clouds)} objects" if len(clouds) > 1 else f"'{clouds[0].obj.name}'"  # what the user selected

    def described(report):
        automatic = report.noise is not None and settings.auto_amount
        noise = f"noise {report.noise.ratio:.2f}x spacing: " if automatic else ""
        return f"{noise}{amount(report)}, alpha {report.alpha:.3g}"

    moved = "; ".join(  # the words of the mesh operators' reports (core.Change.summary)
        core.measure_change(c.positions, c.result).summary().replace("vertices", "points").replace("vertex", "point")
        for c in clouds
    )
    return (
        f"HC Smooth Points on {names}: {points} points, "
        + "; ".join(described(c.report) for c in clouds)
        + f", {seconds:.2f} s"
        + (f", {still} points without RFS faces stayed put" if still else "")
        + f"; {moved}"
    )


def messages(clouds, settings):
    """[(level, text)] to report after a finished run: the summary, then any warnings."""
    found = [("INFO", summary(clouds, settings))]
    for level, text in (
        ("WARNING", stuck_warning(clouds)),
        ("WARNING", core.convergence_message(min(c.report.alpha for c in clouds), settings.beta)),
    ):
        if text:
            found.append((level, text))
    return found
