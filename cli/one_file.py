"""One input file's run, wherever it runs (this process or a batch's worker): its Outcome, the Console
that prints its lines, and ``process``, which smooths it by its route (cli/file_route.py; cli/blend.py for
.blend files) and turns every failure into the outcome's error."""

import os
import sys
import time
import traceback
import warnings
from dataclasses import dataclass, field

from .. import core
from ..jobs import InputError
from ..jobs import mesh as mesh_jobs
from ..settings_spec import PointSettings
from . import arguments, file_route
from .files import FileError

PROGRESS_FIRST = 1.0  # seconds of smoothing before the first progress line
PROGRESS_EVERY = 1.0  # seconds between progress lines at most once they started


def plural(count, word, words=None):
    return f"{count} {word if count == 1 else words or word + 's'}"


@dataclass
class Outcome:
    """What happened to one input file."""

    source: str
    target: str
    objects: int = 0
    vertices: int = 0
    iterations: int = 0  # meshes: the most iterations any mesh ran
    sharp: bool = False  # meshes: Keep Sharp Edges ran (its iterations are steps)
    held: int = 0  # meshes: parts the Automatic Amount left as they were (core.mesh.collapse)
    kept: bool = False  # meshes: every move was kept across the surface (Keep in Place)
    rounds: list = field(default_factory=list)  # point clouds: (rounds, steps per round) per cloud
    seconds: float = 0.0
    changes: list = field(default_factory=list)  # core.Change per smoothed mesh
    legends: list = field(default_factory=list)  # --deviation-attribute: each mesh's deviation map in words
    notes: list = field(default_factory=list)  # how a file too big for memory ran (cli/tiled.py)
    warnings: list = field(default_factory=list)
    error: str = ""
    blender_lines: list = field(default_factory=list)  # what Blender printed while a failed file ran
    stage: str = "reading"  # reading, smoothing, writing, done: where an interrupt found it
    progress: object = None  # called with the fraction done while the file's smoothing runs (Console.progress)

    def change_text(self):
        """core.Change.brief of the mesh that moved furthest (relative to its size)."""
        if not self.changes:
            return "-"
        worst = max(self.changes, key=lambda c: c.max_displacement / c.bbox_diagonal_before if c.moved else 0.0)
        text = worst.brief()
        return text if len(self.changes) == 1 else f"{text} (the furthest of {len(self.changes)} meshes)"

    def amount_text(self):
        """How much smoothing ran: '10 iterations' (and the parts left as they were, if any), or for point
        clouds '3 rounds of 15 steps (45 steps)'."""
        held = f", {mesh_jobs.held_words(self.held)}" if self.held else ""
        held += ", kept in place" if self.kept else ""
        if self.sharp:
            return f"Keep Sharp Edges, {plural(self.iterations, 'step')}{held}"
        if not self.rounds:
            return plural(self.iterations, "iteration") + held
        kinds = sorted(set(self.rounds))
        if len(kinds) == 1:
            ((rounds, steps),) = kinds
            return f"{plural(rounds, 'round')} of {plural(steps, 'step')} ({plural(rounds * steps, 'step')})"
        totals = [rounds * steps for rounds, steps in kinds]
        return f"{min(totals)} to {max(totals)} steps in {' / '.join(f'{r}x{s}' for r, s in kinds)}"

    def size_text(self):
        return plural(self.vertices, "point") if self.rounds else plural(self.vertices, "vertex", "vertices")


class Console:
    """Prints the command's lines; once nobody reads them (`hc_smooth ... | head -1`), drops them quietly
    and goes on with the files."""

    def __init__(self, verbose=False):
        self.verbose = verbose

    def say(self, text, stream=None):
        stream = stream or sys.stdout
        try:
            print(text, file=stream, flush=True)
        except BrokenPipeError:
            # Python would complain again at exit while flushing: point the descriptor at nothing.
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, stream.fileno())
            os.close(devnull)

    def progress(self, outcome, started):
        """A callable for ``Outcome.progress``: prints 'smoothing FILE: 42 %' once the smoothing has run for
        PROGRESS_FIRST seconds, then every PROGRESS_EVERY seconds at most (a long run is never silent)."""
        last = [started + PROGRESS_FIRST - PROGRESS_EVERY]

        def report(fraction):
            now = time.perf_counter()
            if now - last[0] >= PROGRESS_EVERY:
                last[0] = now
                self.say(f"hc_smooth: smoothing {outcome.source}: {100 * fraction:.0f} %")

        return report

    def stage(self, outcome, stage, path):
        outcome.stage = stage
        if self.verbose:
            self.say(f"hc_smooth: {stage} {path}")


def is_blend(path):
    return os.path.splitext(path)[1].lower() == arguments.BLEND


def blend_route():
    """cli/blend.py, or FileError in a Python without Blender."""
    try:
        from . import blend
    except ModuleNotFoundError as error:
        if error.name != "bpy":
            raise
        raise FileError("a .blend file needs Blender: smooth it with `blender -b -c hc_smooth`") from None
    return blend


def point_settings(plan):
    """The point operator's settings with what the command line gave."""
    return PointSettings(**plan.point_options)


def process(outcome, plan, settings, console):
    """Smooth one input file into its target; every failure becomes ``Outcome.error`` (no output written).

    What Blender prints meanwhile is kept off the console and handed to the caller only when the file
    failed (``Outcome.blender_lines``)."""
    start = time.perf_counter()
    bug = None
    with warnings.catch_warnings(record=True) as caught:
        try:
            if is_blend(outcome.source):
                blend_route().smooth_blend_file(outcome, plan, settings, console)
            else:
                file_route.smooth_mesh_file(outcome, plan, settings, console)
        except (FileError, InputError, ValueError, OSError) as error:
            outcome.error = str(error)
        except MemoryError:
            outcome.error = "not enough memory for this file"
        except Exception as error:  # a bug: report it with its traceback and go on with the other files
            bug = traceback.format_exc()
            outcome.error = f"internal error: {type(error).__name__}: {error}"
    outcome.stage = "done"
    if bug:
        console.say(bug.rstrip("\n"), sys.stderr)
    # Python's warnings would have gone to the collected stderr: they are the file's warnings.
    outcome.warnings.extend(
        str(warning.message) for warning in caught if not issubclass(warning.category, core.ConvergenceWarning)
    )  # said at the start
    if outcome.error:
        outcome.blender_lines = [line for line in outcome.blender_lines if line.strip() not in outcome.error]
    else:
        outcome.blender_lines = []
    outcome.seconds = time.perf_counter() - start
