"""`blender -b -c hc_smooth INPUT... -o OUTDIR`: smooth scan files, one progress line per file, a summary.

``main(argv)`` is the function registered with bpy.utils.register_cli_command; tests call it directly
with an argument list (the bpy module cannot run `blender -c`), and scripts/hc_smooth_files.py runs it in
a Python without Blender. PLY, OBJ and STL files take the file route (cli/file_route.py: NumPy and SciPy
only); .blend files are opened in Blender (cli/blend.py, loaded only for them).
"""

import contextlib
import os
import signal
import sys
import threading
import time
import traceback
import warnings
from dataclasses import dataclass, field

from .. import core
from ..jobs import InputError, points
from ..jobs import mesh as mesh_jobs
from ..settings_spec import PointSettings
from . import arguments, batch, file_route, files
from .files import FileError

INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command stopped by Ctrl+C
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


def main(argv, prog=arguments.PROG):
    """Run the command on ``argv`` (the arguments after `-c hc_smooth`); returns the exit status.

    ``prog`` names the command in usage messages (the bpy route gives its own)."""
    console = Console()
    try:
        plan = arguments.parse(argv, prog=prog)
        settings = point_settings(plan) if plan.points else plan.settings
    except SystemExit as done:  # --help printed; argparse exits
        return done.code or 0
    except arguments.UsageError as error:
        console.say(error, sys.stderr)
        return 2
    except OSError as error:  # an input that cannot be looked at (an unreadable folder): no traceback
        console.say(f"{error.filename}: {error.strerror}" if error.filename else str(error), sys.stderr)
        return 2
    console.verbose = plan.verbose
    with interruptible():
        outcomes = []
        try:
            return run(plan, settings, console, outcomes)
        except batch.BatchError as error:  # before any file ran: nothing written
            console.say(f"hc_smooth: {error}", sys.stderr)
            return 2
        except KeyboardInterrupt:
            return interrupted(plan, outcomes, console)


def run(plan, settings, console, outcomes):
    for note in plan.notes:
        console.say(f"hc_smooth: note: {note}")
    if plan.points:
        message = points.convergence_note(settings)
    else:
        hc = settings.method == "HC" and not settings.keep_sharp_edges  # Theorem 5.2 is about HC's umbrella
        message = core.convergence_message(settings.alpha, settings.beta) if hc else None
    if message:
        console.say(f"hc_smooth: warning: {message}")
    for folder in dict.fromkeys(os.path.dirname(target) for _, target in plan.files):
        for name in files.remove_stale_temporaries(folder) if os.path.isdir(folder) else ():
            console.say(f"hc_smooth: note: removed {os.path.join(folder, name)}, left by an interrupted run")
    total = len(plan.files)

    def report(outcome):
        console.say(f"[{len(outcomes)}/{total}] {progress_line(outcome)}")
        for text in outcome.legends + outcome.notes if not outcome.error else ():
            console.say(f"  {text}")
        for text in outcome.warnings:
            console.say(f"  warning: {text}")
        for line in outcome.blender_lines:
            console.say(f"  blender: {line}")

    here, away = split_batch(plan)
    if away:
        if here:
            console.say("hc_smooth: note: .blend files run here, one at a time (the workers have no Blender)")
        batch.smooth_files(plan, away, done=lambda outcome: (outcomes.append(outcome), report(outcome)), failed=lost)
    for source, target in here:
        outcome = Outcome(source=source, target=target)
        outcomes.append(outcome)
        process(outcome, plan, settings, console)
        report(outcome)
    order = {source: index for index, (source, _) in enumerate(plan.files)}
    console.say(summary_table(sorted(outcomes, key=lambda outcome: order[outcome.source])))
    failed = [outcome for outcome in outcomes if outcome.error]
    if failed:
        console.say(f"hc_smooth: {len(failed)} of {total} files failed", sys.stderr)
        return 1
    return 0


def split_batch(plan):
    """(files this process smooths, files the workers smooth): with --jobs or --scheduler, every PLY, OBJ and
    STL file goes to the workers; .blend files stay here (they need Blender)."""
    if not plan.batch:
        return plan.files, []
    blend = [(source, target) for source, target in plan.files if is_blend(source)]
    return blend, [pair for pair in plan.files if not is_blend(pair[0])]


def is_blend(path):
    return os.path.splitext(path)[1].lower() == arguments.BLEND


def lost(source, target, reason):
    """The outcome of a file that no worker could finish (Dask gave up on it: its workers kept dying)."""
    return Outcome(source=source, target=target, error=f"no worker finished it ({reason})", stage="done")


@contextlib.contextmanager
def interruptible():
    """Ctrl+C (SIGINT) raises KeyboardInterrupt while the command runs, whatever Python handler the host
    installed, which comes back afterwards (a handler set from C cannot be put back from Python: Python's
    stays, and the host exits after the command anyway)."""
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)


def interrupted(plan, outcomes, console):
    """What an interrupt left: the files done, the one it stopped (as it was), the ones not started."""
    done = [outcome for outcome in outcomes if outcome.stage == "done" and not outcome.error]
    current = outcomes[-1] if outcomes and outcomes[-1].stage != "done" else None
    untouched = len(plan.files) - len(outcomes) + (current is not None)
    where = f" while {current.stage} {current.source}" if current else ""
    console.say(
        f"hc_smooth: interrupted{where}: {plural(len(done), 'file')} of {len(plan.files)} smoothed; "
        f"{plural(untouched, 'file')} left as {'it was' if untouched == 1 else 'they were'} "
        "(no partial output written)",
        sys.stderr,
    )
    return INTERRUPTED


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


def progress_line(outcome):
    if outcome.error:
        return f"{outcome.source}: FAILED: {outcome.error}"
    return (
        f"{outcome.source} -> {outcome.target}: {outcome.size_text()}, {outcome.amount_text()}, "
        f"{outcome.seconds:.2f} s, {outcome.change_text()}"
    )


def summary_table(outcomes):
    header = ("file", "vertices", "smoothing", "time", "change", "result")
    rows = [header]
    for outcome in outcomes:
        if outcome.error:
            rows.append((outcome.source, "-", "-", f"{outcome.seconds:.2f} s", "-", "FAILED: " + outcome.error))
        else:
            rows.append(
                (
                    outcome.source,
                    str(outcome.vertices),
                    outcome.amount_text(),
                    f"{outcome.seconds:.2f} s",
                    outcome.change_text(),
                    outcome.target,
                )
            )
    widths = [max(len(row[i]) for row in rows) for i in range(len(header) - 1)]
    lines = ["  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + row[-1] for row in rows]
    done = sum(1 for outcome in outcomes if not outcome.error)
    lines.append(f"{done} of {len(outcomes)} files smoothed")
    return "\n".join(lines)
