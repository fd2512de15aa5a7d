"""`blender -b -c hc_smooth INPUT... -o OUTDIR`: smooth scan files, one progress line per file, a summary.

``main(argv)`` is the function registered with bpy.utils.register_cli_command; tests call it directly
with an argument list (the bpy module cannot run `blender -c`). Meshes are smoothed with the shared
job code of the mesh operators (operators/jobs.py), point clouds with that of the point operator
(operators/point_cloud.py): the same functions the operators call, fed from the command line.
"""

import os
import sys
import time
import traceback
import warnings
from dataclasses import dataclass, field

import bpy

from .. import core
from ..operators import jobs as jobs_module
from ..operators import point_cloud
from ..operators.objects import InputError, unique_data
from . import arguments, files
from .console_capture import captured
from .files import FileError


@dataclass
class Outcome:
    """What happened to one input file."""

    source: str
    target: str
    objects: int = 0
    vertices: int = 0
    iterations: int = 0  # meshes: the most iterations any mesh ran
    rounds: list = field(default_factory=list)  # point clouds: (rounds, steps per round) per cloud
    seconds: float = 0.0
    changes: list = field(default_factory=list)  # core.Change per smoothed mesh
    warnings: list = field(default_factory=list)
    error: str = ""
    blender_lines: list = field(default_factory=list)  # what Blender printed while a failed file ran

    def change_text(self):
        if not self.changes:
            return "-"
        worst = max(self.changes, key=lambda c: abs(c.volume_change if c.volume_change is not None else c.bbox_change))
        text = (
            f"volume {worst.volume_change:+.3%}"
            if worst.volume_change is not None
            else f"size {worst.bbox_change:+.3%}"
        )
        return text if len(self.changes) == 1 else f"{text} (largest of {len(self.changes)})"

    def amount_text(self):
        """How much smoothing ran: '10 iterations', or for point clouds '3 rounds of 15 steps (45 steps)'."""
        if not self.rounds:
            return f"{self.iterations} iterations"
        kinds = sorted(set(self.rounds))
        if len(kinds) == 1:
            ((rounds, steps),) = kinds
            return f"{rounds} rounds of {steps} steps ({rounds * steps} steps)"
        totals = [rounds * steps for rounds, steps in kinds]
        return f"{min(totals)} to {max(totals)} steps in {' / '.join(f'{r}x{s}' for r, s in kinds)}"

    def size_text(self):
        return f"{self.vertices} {'points' if self.rounds else 'vertices'}"


def main(argv):
    """Run the command on ``argv`` (the arguments after `-c hc_smooth`); returns the exit status."""
    try:
        plan = arguments.parse(argv)
        settings = point_settings(plan) if plan.points else plan.settings
    except SystemExit as done:  # --help printed; argparse exits
        return done.code or 0
    except arguments.UsageError as error:
        print(error, file=sys.stderr)
        return 2
    except OSError as error:  # an input that cannot be looked at (an unreadable folder): no traceback
        print(f"{error.filename}: {error.strerror}" if error.filename else str(error), file=sys.stderr)
        return 2
    for note in plan.notes:
        print(f"hc_smooth: note: {note}")
    if plan.points:
        message = point_cloud.convergence_note(settings)
    else:
        message = core.convergence_message(settings.alpha, settings.beta) if settings.method == "HC" else None
    if message:
        print(f"hc_smooth: warning: {message}")
    outcomes, cleaned = [], set()
    total = len(plan.files)
    for number, (source, target) in enumerate(plan.files, 1):
        folder = os.path.dirname(target)
        if folder not in cleaned and os.path.isdir(folder):
            cleaned.add(folder)
            for name in files.remove_stale_temporaries(folder):
                print(f"hc_smooth: note: removed {os.path.join(folder, name)}, left by an interrupted run")
        outcome = process(source, target, plan, settings)
        outcomes.append(outcome)
        print(f"[{number}/{total}] {progress_line(outcome)}", flush=True)
        for text in outcome.warnings:
            print(f"  warning: {text}", flush=True)
        for line in outcome.blender_lines:
            print(f"  blender: {line}", flush=True)
    print(summary_table(outcomes), flush=True)
    failed = [outcome for outcome in outcomes if outcome.error]
    if failed:
        print(f"hc_smooth: {len(failed)} of {total} files failed", file=sys.stderr, flush=True)
        return 1
    return 0


def point_settings(plan):
    """The point operator's settings with what the command line gave."""
    return point_cloud.PointSettings(**plan.point_options)


def process(source, target, plan, settings):
    """Smooth one input file into ``target``; every failure becomes ``Outcome.error`` (no output written).

    What Blender prints meanwhile (its importers' and exporters' reports) is kept off the console and
    handed to the caller only when the file failed (``Outcome.blender_lines``)."""
    outcome = Outcome(source=source, target=target)
    start = time.perf_counter()
    bug = None
    with captured() as printed, warnings.catch_warnings(record=True) as caught:
        try:
            if os.path.splitext(source)[1].lower() == arguments.BLEND:
                smooth_blend_file(source, target, plan, settings, outcome)
            else:
                smooth_mesh_file(source, target, plan, settings, outcome)
        except (FileError, InputError, ValueError, OSError) as error:
            outcome.error = str(error)
        except MemoryError:
            outcome.error = "not enough memory for this file"
        except Exception as error:  # a bug: report it with its traceback and go on with the other files
            bug = traceback.format_exc()
            outcome.error = f"internal error: {type(error).__name__}: {error}"
    if bug:
        print(bug, end="", file=sys.stderr, flush=True)
    # Python's warnings would have gone to the collected stderr: they are the file's warnings.
    outcome.warnings.extend(
        str(warning.message) for warning in caught if not issubclass(warning.category, core.ConvergenceWarning)
    )  # said at the start
    if outcome.error:
        outcome.blender_lines = [line for line in printed if line.strip() not in outcome.error]
    outcome.seconds = time.perf_counter() - start
    return outcome


def smooth_mesh_file(source, target, plan, settings, outcome):
    bpy.ops.wm.read_homefile(use_empty=True)  # each file starts from an empty scene
    objects = files.import_file(source, result_ext=os.path.splitext(target)[1].lower())
    meshes = [obj for obj in objects if obj.type == "MESH"]
    if not meshes:
        raise FileError("no mesh in this file")
    layout = files.read_layout(source)  # what the result keeps of the input: encoding, normals, materials
    smooth_objects(meshes, plan, settings, outcome)
    files.export_file(meshes, target, layout)


def is_point_cloud(obj):
    return obj.type == "POINTCLOUD" or (obj.type == "MESH" and bool(len(obj.data.vertices)) and not len(obj.data.edges))


def smooth_blend_file(source, target, plan, settings, outcome):
    if not os.path.isfile(source):
        raise FileError("no such file")
    try:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(source), load_ui=False)
    except RuntimeError as error:
        raise FileError(f"could not open the .blend file: {str(error).strip()}") from None
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
    smooth_objects(objects, plan, settings, outcome)
    files.save_blend_copy(target)


def smooth_objects(objects, plan, settings, outcome):
    """Smooth the objects as meshes, or as point clouds with --points; everything is read before anything is written."""
    if plan.points:
        smooth_point_clouds(objects, settings, outcome)
    else:
        smooth_meshes(objects, settings, outcome)
    outcome.objects = len(objects)


def smooth_meshes(objects, settings, outcome):
    """A mesh shared by several objects is smoothed once."""
    for obj in objects:
        if obj.type != "MESH":
            raise FileError(
                f"'{obj.name}' is a {obj.type.lower().replace('_', ' ')} object, not a mesh"
                + (" (pass --points to smooth it)" if obj.type == "POINTCLOUD" else "")
            )
        if is_point_cloud(obj):
            raise FileError(f"'{obj.name}' has no edges: it is a point cloud (pass --points to smooth it as one)")
    jobs = [jobs_module.make_job(obj, settings) for obj in unique_data(objects)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)  # said once, at the start
        for _ in jobs_module.run(jobs, settings):
            pass
    for job in jobs:
        jobs_module.write(job, settings)
        outcome.changes.append(jobs_module.measure(job))
        outcome.vertices += len(job.positions)
        outcome.iterations = max(outcome.iterations, job.iterations_run)


def smooth_point_clouds(objects, settings, outcome):
    """With the point operator's own functions (read, run, write), ``settings`` a point_cloud.PointSettings."""
    for obj in objects:
        if obj.type == "MESH" and (len(obj.data.edges) or len(obj.data.polygons)):
            raise FileError(f"'{obj.name}' has edges: it is a mesh, not a point cloud (smooth it without --points)")
    clouds = point_cloud.read_clouds(objects, settings)
    for _ in point_cloud.run(clouds, settings):
        pass
    point_cloud.write(clouds, settings, bpy.context)
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
