"""Command-line arguments of `blender -b -c hc_smooth` and the plan of which file goes where.

No bpy here: parsing and planning are plain Python, so a bad command line fails before Blender
imports anything.
"""

import argparse
import math
import mmap
import os
import re
from dataclasses import dataclass, field

MESH_FORMATS = (".ply", ".obj", ".stl")
BLEND = ".blend"
METHODS = ("HC", "LAPLACIAN", "LAPLACIAN_CENTRAL", "LAPLACIAN_ORIGINAL")
MODES = ("SIMULTANEOUS", "SEQUENTIAL")

DESCRIPTION = """\
Smooth scanned meshes without shrinking them (HC algorithm, Vollmer, Mencl, Mueller 1999).
Reads PLY, OBJ and STL files with Blender's own importers, smooths every mesh with the same code as
the Object > HC Smooth operator, and writes the result in the same format (or --format) into OUTDIR.
A .blend input is opened, its mesh objects (or those named with --object) are smoothed and a copy is
saved into OUTDIR. Directories given as INPUT stand for the PLY/OBJ/STL/.blend files directly in them
(hidden files skipped); a file named twice is smoothed once. A file that fails leaves no output behind.

Existing files are never replaced, except the input itself with --in-place (same path, same format)
and, with --overwrite, existing results (and their .mtl for OBJ). --in-place with --format writes a
new file beside the input and keeps the input. Everything is checked before anything runs.

--points smooths point clouds (meshes without edges) with the Object > HC Smooth Points code. They
take --alpha, --beta, --rounds, --steps-per-round, --neighbours, --reach, --gap, --fixed-group and
--invert-group; the mesh-only options (--iterations, --mode, --tolerance, --method, --pin-boundary)
are refused with --points, and the point options without it.
"""

EPILOG = """\
exit status: 0 when every file was smoothed, 1 when any file failed (the reason is printed),
2 for a bad command line (nothing is read or written).

examples:
  blender -b -c hc_smooth scans/*.ply -o smoothed/
  blender -b -c hc_smooth scan.obj -o out/ --iterations 20 --alpha 0.2 --beta 0.7 --format ply
  blender -b -c hc_smooth scene.blend --object Scan --fixed-group Keep -o out/
  blender -b -c hc_smooth points.ply --points --rounds 4 -o out/
  ls scans/*.ply | xargs -P 4 -n 1 blender -b -c hc_smooth -o smoothed/    (one process per file)
"""

# The point operator's defaults (operators/point_cloud.PointSettings, which needs bpy), for --help;
# tests/blender/test_cli.py checks they agree.
POINT_DEFAULTS = {"rounds": 3, "steps_per_round": 22, "neighbours": 16, "reach": 2.5, "gap": 3.0}
# Command-line name -> PointSettings field.
POINT_FIELDS = {"alpha": "alpha", "beta": "beta", "rounds": "rounds", "steps_per_round": "iterations_per_round",
                "neighbours": "neighbours", "reach": "spacing_factor", "gap": "gap_factor",
                "fixed_group": "vertex_group", "invert_group": "invert_vertex_group"}
POINT_ONLY = ("rounds", "steps_per_round", "neighbours", "reach", "gap")
# Mesh-only options, and the value each may keep with --points because it describes what runs anyway.
MESH_ONLY = {"iterations": None, "mode": "SIMULTANEOUS", "tolerance": 0.0, "method": "HC", "pin_boundary": False}


class UsageError(Exception):
    """A bad command line: nothing has been read or written."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # raise instead of sys.exit: the command returns its status to Blender
        raise UsageError(f"{self.prog}: error: {message}")


def _number(text):
    value = float(text)
    if not math.isfinite(value):  # nan passes no comparison and inf no limit: refuse both here
        raise argparse.ArgumentTypeError(f"{text} is not a finite number")
    return value


def _unit_interval(text):
    value = _number(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text} is outside [0, 1]")
    return value


def _non_negative_float(text):
    value = _number(text)
    if value < 0.0:
        raise argparse.ArgumentTypeError(f"{text} is negative")
    return value


def _positive_float(text):
    value = _number(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"{text} is not above 0")
    return value


def _whole(low):
    def parse(text):
        value = int(text)
        if value < low:
            raise argparse.ArgumentTypeError(f"{text} is negative" if low == 0 else f"{text} is below {low}")
        return value
    parse.__name__ = "whole number"  # argparse names the type in its "invalid ... value" message
    return parse


def make_parser():
    parser = _Parser(prog="blender -b -c hc_smooth", description=DESCRIPTION, epilog=EPILOG,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("inputs", nargs="+", metavar="INPUT", help="PLY, OBJ, STL or .blend files, or directories")
    where = parser.add_argument_group("where results go")
    where.add_argument("-o", "--output-dir", metavar="OUTDIR", help="folder for the results (created if missing)")
    where.add_argument("--in-place", action="store_true",
                       help="write each result beside its input, replacing the input file (with --format: a new "
                            "file beside the input, which is kept)")
    where.add_argument("--format", choices=("ply", "obj", "stl"), type=str.lower,
                       help="write mesh files in this format (default: the input's); .blend stays .blend")
    where.add_argument("--overwrite", action="store_true",
                       help="replace results that already exist (and the .mtl beside an OBJ result); without it "
                            "an existing file that is not the input of --in-place stops the run before it starts")
    smoothing = parser.add_argument_group("smoothing (as the operators' properties)")
    smoothing.add_argument("--method", choices=METHODS, type=str.upper, default=None,
                           help="HC (default) or a Laplacian variant; meshes only")
    smoothing.add_argument("--alpha", type=_unit_interval, default=None,
                           help="pull towards the original (0.1; point clouds: chosen from the noise unless given, "
                                "then --steps-per-round applies)")
    smoothing.add_argument("--beta", type=_unit_interval, default=None,
                           help="HC correction weight (0.6; point clouds: 0.55)")
    smoothing.add_argument("--iterations", type=_whole(0), default=None, help="iterations (10); meshes only")
    smoothing.add_argument("--mode", choices=MODES, type=str.upper, default=None,
                           help="SIMULTANEOUS (default) or SEQUENTIAL; meshes only")
    smoothing.add_argument("--tolerance", type=_non_negative_float, default=None,
                           help="stop early below this move (fraction of the bounding-box diagonal; 0); meshes only")
    smoothing.add_argument("--fixed-group", metavar="NAME", default="",
                           help="vertices (points) in this vertex group stay fixed (.blend, OBJ groups)")
    smoothing.add_argument("--invert-group", action="store_true",
                           help="fix everything outside --fixed-group instead (smooth only the group)")
    smoothing.add_argument("--pin-boundary", action="store_true",
                           help="keep open-boundary vertices fixed; meshes only")
    smoothing.add_argument("--object", dest="objects", action="append", default=[], metavar="NAME",
                           help=".blend inputs: smooth this object (repeatable; default: every mesh object, with "
                                "--points every point cloud)")
    points = parser.add_argument_group("point clouds (as Object > HC Smooth Points)")
    points.add_argument("--points", action="store_true",
                        help="smooth point clouds (meshes without edges; .blend: also point cloud objects) "
                             "instead of meshes")
    points.add_argument("--rounds", type=_whole(0), default=None,
                        help=f"runs of HC steps with edge swapping between them ({POINT_DEFAULTS['rounds']})")
    points.add_argument("--steps-per-round", type=_whole(1), default=None, metavar="N",
                        help="HC steps per round (chosen from the noise unless given, then "
                             f"{POINT_DEFAULTS['steps_per_round']} and --alpha apply)")
    points.add_argument("--neighbours", type=_whole(2), default=None, metavar="N",
                        help=f"nearest neighbours a point may connect to ({POINT_DEFAULTS['neighbours']})")
    points.add_argument("--reach", type=_positive_float, default=None, metavar="R",
                        help=f"connect neighbours up to R local spacings ({POINT_DEFAULTS['reach']})")
    points.add_argument("--gap", type=_positive_float, default=None, metavar="G",
                        help=f"never connect across a gap of G local spacings ({POINT_DEFAULTS['gap']}; "
                             "at least --reach)")
    return parser


@dataclass
class Settings:
    """The operator properties jobs.make_job/run/write read, filled from the command line."""

    method: str = "HC"
    alpha: float = 0.1
    beta: float = 0.6
    iterations: int = 10
    mode: str = "SIMULTANEOUS"
    tolerance: float = 0.0
    vertex_group: str = ""
    invert_vertex_group: bool = False
    pin_boundary: bool = False
    output: str = "MESH"


@dataclass
class Plan:
    settings: Settings  # the mesh settings (unused with --points)
    files: list  # [(input path, output path)]
    points: bool = False
    point_options: dict = field(default_factory=dict)  # PointSettings fields given on the command line
    objects: list = field(default_factory=list)
    notes: list = field(default_factory=list)  # said before the run (an input named twice)


def _option(name):
    return "--" + name.replace("_", "-")


def parse(argv):
    """argv (the arguments after `-c hc_smooth`) -> Plan; raises UsageError, or SystemExit(0) for --help.

    Reads the file system (which inputs and outputs exist) but changes nothing on it."""
    args = make_parser().parse_args(list(argv))
    if args.in_place == bool(args.output_dir):
        raise UsageError("give either -o OUTDIR or --in-place (inputs are never overwritten otherwise)")
    if args.invert_group and not args.fixed_group:
        raise UsageError("--invert-group needs --fixed-group NAME")
    if args.points:
        refused = [_option(name) for name, keeps in MESH_ONLY.items()
                   if getattr(args, name) not in (None, keeps)]
        if refused:
            raise UsageError(f"{', '.join(refused)} {'does' if len(refused) == 1 else 'do'} not apply to point "
                             "clouds (--points): they take --alpha, --beta, --rounds, --steps-per-round, "
                             "--neighbours, --reach, --gap, --fixed-group and --invert-group")
    else:
        given = [_option(name) for name in POINT_ONLY if getattr(args, name) is not None]
        if given:
            raise UsageError(f"{', '.join(given)} {'applies' if len(given) == 1 else 'apply'} to point clouds "
                             "only: add --points")
    settings = Settings()
    for name in ("method", "alpha", "beta", "iterations", "mode", "tolerance"):
        if getattr(args, name) is not None:
            setattr(settings, name, getattr(args, name))
    settings.vertex_group, settings.invert_vertex_group = args.fixed_group, args.invert_group
    settings.pin_boundary = args.pin_boundary
    point_options = {POINT_FIELDS[name]: getattr(args, name) for name in POINT_FIELDS
                     if getattr(args, name) is not None}
    if "alpha" in point_options or "iterations_per_round" in point_options:
        point_options["auto_amount"] = False  # as the operator: a manual amount uses alpha and steps as set
    inputs, notes = expand_inputs(args.inputs)
    if args.objects and not any(os.path.splitext(path)[1].lower() == BLEND for path in inputs):
        raise UsageError("--object names objects inside .blend files, and no input is a .blend file "
                         "(PLY, OBJ and STL inputs are smoothed whole)")
    files = plan_outputs(inputs, args.output_dir, args.format, args.in_place, args.overwrite)
    return Plan(settings=settings, files=files, points=args.points, point_options=point_options,
                objects=args.objects, notes=notes)


def _key(path):
    return os.path.normcase(os.path.realpath(path))


def expand_inputs(paths):
    """-> (files, notes). Files as given (any extension: an unsupported one fails that file); directories ->
    the supported files directly in them, hidden ones skipped (._* metadata, temporaries of a killed run).
    A file named twice (also through a folder, a ./ or a link) is kept once, with a note."""
    found, notes, first = [], [], {}
    for path in paths:
        if os.path.isdir(path):
            entries = sorted(entry.path for entry in os.scandir(path) if entry.is_file()
                             and not entry.name.startswith(".")
                             and os.path.splitext(entry.name)[1].lower() in MESH_FORMATS + (BLEND,))
            if not entries:
                raise UsageError(f"{path}: no PLY, OBJ, STL or .blend files in this folder")
        else:
            entries = [path]
        for entry in entries:
            key = _key(entry)
            if key in first:
                same = "" if entry == first[key] else f" (the same file as {first[key]})"
                notes.append(f"{entry} is named more than once{same}: smoothing it once")
                continue
            first[key] = entry
            found.append(entry)
    return found, notes


def output_path(path, output_dir, fmt, in_place):
    stem, ext = os.path.splitext(os.path.basename(path))
    if fmt and ext.lower() in MESH_FORMATS:
        ext = "." + fmt
    folder = os.path.dirname(os.path.abspath(path)) if in_place else os.path.abspath(output_dir)
    return os.path.join(folder, stem + ext)


def companions(target):
    """Files written beside ``target``: the material library of an OBJ result."""
    stem, ext = os.path.splitext(target)
    return [stem + ".mtl"] if ext.lower() == ".obj" else []


def material_libraries(obj_path):
    """Real paths of the .mtl files an OBJ file names in its `mtllib` lines (empty if it cannot be read)."""
    folder = os.path.dirname(os.path.abspath(obj_path))
    try:
        with open(obj_path, "rb") as source, mmap.mmap(source.fileno(), 0, access=mmap.ACCESS_READ) as data:
            lines = [match.group(1).decode("utf-8", "replace").strip()
                     for match in re.finditer(rb"^mtllib[ \t]+([^\r\n]+)", data, re.M)]
    except (OSError, ValueError):  # unreadable or empty: it names none (reading it fails that file later)
        return set()
    names = {name for line in lines for name in (line, *line.split())}  # one name with spaces, or several
    return {_key(os.path.join(folder, name)) for name in names}


def plan_outputs(inputs, output_dir, fmt, in_place, overwrite=False):
    """[(input, output)], refusing to write one output twice, over any input (without --in-place), or over
    any existing file that is not the input replaced in place (without --overwrite)."""
    sources = {_key(path) for path in inputs}
    plan, taken, existing = [], {}, []
    for path in inputs:
        target = output_path(path, output_dir, fmt, in_place)
        key = _key(target)
        if key in taken:
            raise UsageError(f"{path} and {taken[key]} would both be written to {target}: "
                             "smooth them into different folders")
        same = key == _key(path)
        if key in sources and not (in_place and same):
            raise UsageError(f"{path}: the result would overwrite an input ({target}); "
                             + ("choose another -o OUTDIR or pass --in-place" if not in_place
                                else "smooth it into a folder with -o OUTDIR"))
        taken[key] = path
        plan.append((path, target))
        if overwrite:
            continue
        if os.path.lexists(target) and not (in_place and same):
            existing.append(target)
        for extra in companions(target):
            # In place, the .mtl the input OBJ names is part of the input; any other one is someone else's.
            if os.path.lexists(extra) and not (in_place and same and _key(extra) in material_libraries(path)):
                existing.append(extra)
    if existing:
        names = "".join(f"\n  {name}" for name in existing)
        where = "move them away or smooth into a folder with -o OUTDIR" if in_place else "choose another -o OUTDIR"
        raise UsageError(f"these files exist and would be replaced:{names}\n{where}, or pass --overwrite to replace "
                         "them (nothing was read or written)")
    return plan
