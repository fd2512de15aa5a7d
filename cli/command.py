"""`blender -b -c hc_smooth INPUT... -o OUTDIR`: smooth scan files, one progress line per file, a summary.

``main(argv)`` is the function registered with bpy.utils.register_cli_command; tests call it directly
with an argument list (the bpy module cannot run `blender -c`). PLY, OBJ and STL files are read and
written by cli/formats (NumPy); their arrays go to core without Blender (``smooth_arrays``), in the
precision the file stores, through the shared job code of the mesh operators (operators/jobs.py) and
that of the point operator (operators/point_cloud.py). .blend files are opened, their objects smoothed
by the same job code and saved as a copy.
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

import bpy
import numpy as np

from .. import core
from ..console_capture import captured
from ..operators import jobs as jobs_module
from ..operators import mesh_io, point_cloud
from ..operators.objects import InputError, unique_data
from . import arguments, files, tiled
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
        held = f", {jobs_module.held_words(self.held)}" if self.held else ""
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
        except KeyboardInterrupt:
            return interrupted(plan, outcomes, console)


def run(plan, settings, console, outcomes):
    for note in plan.notes:
        console.say(f"hc_smooth: note: {note}")
    if plan.points:
        message = point_cloud.convergence_note(settings)
    else:
        hc = settings.method == "HC" and not settings.keep_sharp_edges  # Theorem 5.2 is about HC's umbrella
        message = core.convergence_message(settings.alpha, settings.beta) if hc else None
    if message:
        console.say(f"hc_smooth: warning: {message}")
    cleaned = set()
    total = len(plan.files)
    for number, (source, target) in enumerate(plan.files, 1):
        folder = os.path.dirname(target)
        if folder not in cleaned and os.path.isdir(folder):
            cleaned.add(folder)
            for name in files.remove_stale_temporaries(folder):
                console.say(f"hc_smooth: note: removed {os.path.join(folder, name)}, left by an interrupted run")
        outcome = Outcome(source=source, target=target)
        outcomes.append(outcome)
        process(outcome, plan, settings, console)
        console.say(f"[{number}/{total}] {progress_line(outcome)}")
        for text in outcome.legends + outcome.notes if not outcome.error else ():
            console.say(f"  {text}")
        for text in outcome.warnings:
            console.say(f"  warning: {text}")
        for line in outcome.blender_lines:
            console.say(f"  blender: {line}")
    console.say(summary_table(outcomes))
    failed = [outcome for outcome in outcomes if outcome.error]
    if failed:
        console.say(f"hc_smooth: {len(failed)} of {total} files failed", sys.stderr)
        return 1
    return 0


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


def ctrl_c_interrupts():
    """Make Ctrl+C raise KeyboardInterrupt again (after Blender loaded a file, which may set its own
    handler); only inside the command's ``interruptible`` span, on the main thread."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is not (
        signal.default_int_handler
    ):
        signal.signal(signal.SIGINT, signal.default_int_handler)


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


def point_settings(plan):
    """The point operator's settings with what the command line gave."""
    return point_cloud.PointSettings(**plan.point_options)


def process(outcome, plan, settings, console):
    """Smooth one input file into its target; every failure becomes ``Outcome.error`` (no output written).

    What Blender prints meanwhile is kept off the console and handed to the caller only when the file
    failed (``Outcome.blender_lines``)."""
    start = time.perf_counter()
    bug = None
    with warnings.catch_warnings(record=True) as caught:
        try:
            if os.path.splitext(outcome.source)[1].lower() == arguments.BLEND:
                smooth_blend_file(outcome, plan, settings, console)
            else:
                smooth_mesh_file(outcome, plan, settings, console)
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


@contextlib.contextmanager
def in_blender(outcome):
    """Blender's part of a file, with what it prints collected into the outcome (shown if the file fails)."""
    lines = []
    try:
        with captured() as lines:
            yield
    finally:
        outcome.blender_lines.extend(lines)


def smooth_mesh_file(outcome, plan, settings, console):
    limit = plan.memory_limit or tiled.default_memory_limit()
    if tiled.needs_tiles(outcome.source, limit) and tiles_apply(outcome, plan, limit):
        smooth_tiled_file(outcome, plan, settings, console, limit)
        return
    console.stage(outcome, "reading", outcome.source)
    mesh = files.read_mesh(outcome.source)
    console.stage(outcome, "smoothing", outcome.source)
    outcome.progress = console.progress(outcome, time.perf_counter())
    name = os.path.splitext(os.path.basename(outcome.source))[0]
    wanted = {plan.settings.vertex_group, plan.settings.influence_group} - {""}
    groups = mesh.groups(wanted) if wanted and hasattr(mesh, "groups") else {}
    positions = mesh.positions.astype(mesh.precision, copy=False)  # no copy when the file holds doubles
    result, added = smooth_arrays(name, positions, mesh.corners, mesh.sizes, plan, settings, outcome, groups)
    console.stage(outcome, "writing", outcome.target)
    files.write_bytes(outcome.target, files.result_bytes(mesh, result, outcome.target, added))


def tiles_apply(outcome, plan, limit):
    """Whether a file too big for ``limit`` goes in tiles: a binary PLY mesh does; anything else runs whole,
    with a warning, or fails when the limit was given (--memory-limit)."""
    problem = None
    if plan.points:
        problem = "point clouds are smoothed whole"
    elif os.path.splitext(outcome.source)[1].lower() != ".ply":
        problem = "only binary PLY meshes are smoothed in tiles"
    else:
        try:
            tiled.PlyBlocks(outcome.source)
        except (tiled.FormatError, OSError) as error:
            problem = f"it cannot be smoothed in tiles: {error}"
    if problem is None:
        return True
    needed = tiled.size_words(tiled.in_core_bytes(tiled.estimated_vertices(outcome.source)))
    if plan.memory_limit:
        raise FileError(
            f"its whole run would take about {needed}, above --memory-limit {tiled.size_words(limit)}, and {problem}"
        )
    outcome.warnings.append(f"its whole run may take about {needed}, above {tiled.size_words(limit)}; {problem}")
    return False


def smooth_tiled_file(outcome, plan, settings, console, limit):
    """A binary PLY file larger than the memory limit, smoothed in tiles straight into its target (cli/tiled.py)."""
    console.stage(outcome, "smoothing", outcome.source)
    name = os.path.splitext(os.path.basename(outcome.source))[0]
    if os.path.splitext(outcome.target)[1].lower() != ".ply":
        raise FileError("a scan smoothed in tiles is written as it is read (binary PLY): --format cannot convert it")
    if plan.settings.deviation_map:
        raise FileError(
            "--deviation-attribute adds a value to every vertex record, which a scan smoothed in tiles cannot"
        )
    for group in (plan.settings.vertex_group, plan.settings.influence_group):
        group_mask(name, {}, group, False, 0)  # a PLY file has no vertex groups: the whole route's message
    options = jobs_module.core_options(settings, plan.given)
    run = tiled.smooth_file(outcome.source, outcome.target, options, limit, say=lambda text: console.say(f"  {text}"))
    outcome.objects, outcome.vertices, outcome.iterations = 1, run.vertices, run.iterations
    outcome.kept = run.kept_in_place
    outcome.changes.append(run.change)
    outcome.notes.extend(run.notes)


def smooth_arrays(name, positions, corners, sizes, plan, settings, outcome, groups=None):
    """(smoothed positions, {name: vertex values}) of a file's mesh: vertex ``positions`` (in the precision
    the smoothing runs in) and faces given as ``corners`` (vertex indices, face after face) with ``sizes``
    (corners per face; faces of fewer than three corners, or with a corner repeating the one before it,
    take no part). No faces: a point cloud (--points). ``groups``: {name: vertex indices} for
    --fixed-group and --influence-group (an OBJ's groups, weight 1). ``name`` is what messages call the
    mesh. The values are what the file takes besides the positions: the deviation map with
    --deviation-attribute, else none.

    The one place that hands a file's arrays to the smoothing, through the operators' job code (the same
    options and checks, the same core run) but not through a Blender mesh, which would hold them in
    single precision."""
    n = len(positions)
    fixed = group_mask(name, groups, plan.settings.vertex_group, plan.settings.invert_vertex_group, n)
    if plan.points:
        if np.any(sizes >= 3):
            raise FileError(f"'{name}' has edges: it is a mesh, not a point cloud (smooth it without --points)")
        check_point_groups(plan.settings)
        point_cloud.check_settings(settings)  # as read_clouds checks an object's
        cloud = point_cloud.Cloud.of_arrays(name, positions, fixed)
        smooth_clouds([cloud], settings, outcome)
        outcome.objects = 1
        return cloud.result, {}
    influence = group_mask(name, groups, plan.settings.influence_group, plan.settings.invert_influence_group, n)
    job = mesh_job(name, positions, corners, sizes, fixed, None if influence is None else influence.astype(float))
    smooth_jobs([job], settings, outcome, plan.given)
    outcome.objects = 1
    added = {}
    if plan.settings.deviation_map:
        added[mesh_io.DEVIATION_ATTRIBUTE] = jobs_module.deviation_map(job).deviation.astype(np.float32)
    return job.result, added


def check_point_groups(settings):
    if settings.influence_group:
        raise FileError("--influence-group is for meshes: point clouds take --fixed-group only")


def group_mask(name, groups, group, invert, n):
    """The ``n`` vertices' membership of vertex group ``group`` (bool, inverted if asked), None without one."""
    if not group:
        return None
    members = (groups or {}).get(group)
    if members is None:
        raise FileError(f"Object '{name}' has no vertex group '{group}'")
    mask = np.zeros(n, dtype=bool)
    mask[members] = True
    return ~mask if invert else mask


def mesh_job(name, positions, corners, sizes, fixed, influence):
    """A job of the mesh operators (operators/jobs.py) for a file's arrays: its edges are the sides of
    the faces Blender would keep (at least three corners, none repeating the one before it)."""
    n = len(positions)
    if n == 0:
        raise FileError(f"Mesh '{name}' has no vertices: nothing to smooth")
    edges, faces = tiled.surface_arrays(corners, sizes)
    if not len(edges):
        raise FileError(f"'{name}' has no edges: it is a point cloud (pass --points to smooth it as one)")
    fixed = np.zeros(n, dtype=bool) if fixed is None else fixed
    return jobs_module.Job(None, None, positions, edges, faces, fixed, closed=None, influence=influence)


def is_point_cloud(obj):
    return obj.type == "POINTCLOUD" or (obj.type == "MESH" and bool(len(obj.data.vertices)) and not len(obj.data.edges))


def smooth_blend_file(outcome, plan, settings, console):
    source = outcome.source
    console.stage(outcome, "reading", source)
    if not os.path.isfile(source):
        raise FileError("no such file")
    files.check_blend_version(files.blend_version(source), bpy.app.version)
    with in_blender(outcome):
        try:
            bpy.ops.wm.open_mainfile(filepath=os.path.abspath(source), load_ui=False)
            ctrl_c_interrupts()
        except RuntimeError as error:
            raise FileError(f"could not open the .blend file: {str(error).strip()}") from None
    files.check_blend_version(bpy.data.version, bpy.app.version)  # a header this could not read
    console.stage(outcome, "smoothing", source)
    if plan.objects:
        objects = []
        for name in plan.objects:
            obj = bpy.data.objects.get(name)
            if obj is None:
                raise FileError(f"no object '{name}' in this file")
            objects.append(obj)
    else:
        local = [obj for obj in bpy.data.objects if obj.library is None and obj.type in ("MESH", "POINTCLOUD")]
        objects = [obj for obj in local if is_point_cloud(obj) == plan.points]  # --points: the clouds, else the meshes
        others = [obj.name for obj in local if obj not in objects]
        if not objects:
            raise FileError(
                "no local point clouds (meshes without edges, point cloud objects) in this file"
                + (" (it has meshes: smooth them without --points)" if others else "")
                if plan.points
                else "no local mesh objects in this file" + (" (it has point clouds: pass --points)" if others else "")
            )
        if others:
            outcome.warnings.append(
                f"left as they are: {', '.join(sorted(others))} ("
                + (
                    "meshes: smooth them without --points)"
                    if plan.points
                    else "point clouds: smooth them with --points)"
                )
            )
    with in_blender(outcome):
        smooth_objects(objects, plan, settings, outcome)
    console.stage(outcome, "writing", outcome.target)
    with in_blender(outcome):
        files.save_blend_copy(outcome.target)


def smooth_objects(objects, plan, settings, outcome):
    """Smooth the objects as meshes, or as point clouds with --points; everything is read before anything is written."""
    if plan.points:
        smooth_point_clouds(objects, settings, outcome)
    else:
        smooth_meshes(objects, settings, outcome, plan.given)
    outcome.objects = len(objects)


def smooth_meshes(objects, settings, outcome, given=frozenset()):
    """A mesh shared by several objects is smoothed once. ``given``: the settings named on the command line."""
    for obj in objects:
        if obj.type != "MESH":
            raise FileError(
                f"'{obj.name}' is a {obj.type.lower().replace('_', ' ')} object, not a mesh"
                + (" (pass --points to smooth it)" if obj.type == "POINTCLOUD" else "")
            )
        if is_point_cloud(obj):
            raise FileError(f"'{obj.name}' has no edges: it is a point cloud (pass --points to smooth it as one)")
    jobs = [jobs_module.make_job(obj, settings) for obj in unique_data(objects)]
    smooth_jobs(jobs, settings, outcome, given)
    jobs_module.write_all(jobs, settings)


def smooth_jobs(jobs, settings, outcome, given):
    """Run the mesh operators' jobs and count what they did into ``outcome``; writes nothing."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)  # said once, at the start
        # chunk=1: a slice an iteration, the same result as in one go; the slices give the progress lines
        for fraction in jobs_module.run(jobs, settings, chunk=1 if outcome.progress else None, given=given):
            if outcome.progress:
                outcome.progress(fraction)
    for job in jobs:
        outcome.changes.append(jobs_module.measure(job))
        if settings.deviation_map:
            legend = jobs_module.map_legend(job)
            outcome.legends.append(f"'{job.obj.name}': {legend}" if len(jobs) > 1 else legend)
        outcome.vertices += len(job.positions)
        outcome.iterations = max(outcome.iterations, job.report.iterations)
        outcome.sharp = outcome.sharp or job.report.keep_sharp_edges
        outcome.held += job.report.held_parts
        outcome.kept = outcome.kept or job.report.kept_in_place


def smooth_point_clouds(objects, settings, outcome):
    """With the point operator's own functions (read, run, write), ``settings`` a point_cloud.PointSettings."""
    for obj in objects:
        if obj.type == "MESH" and (len(obj.data.edges) or len(obj.data.polygons)):
            raise FileError(f"'{obj.name}' has edges: it is a mesh, not a point cloud (smooth it without --points)")
    clouds = point_cloud.read_clouds(objects, settings)
    smooth_clouds(clouds, settings, outcome)
    point_cloud.write(clouds, settings, bpy.context)


def smooth_clouds(clouds, settings, outcome):
    """Run the point operator's clouds and count what they did into ``outcome``; writes nothing."""
    for _ in point_cloud.run(clouds, settings):
        pass
    for cloud in clouds:
        outcome.changes.append(core.measure_change(cloud.positions, cloud.result))
        outcome.vertices += len(cloud.positions)
        outcome.rounds.append((cloud.report.rounds, cloud.report.iterations_per_round))
    outcome.warnings.extend(text for text in (point_cloud.stuck_warning(clouds),) if text)


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
