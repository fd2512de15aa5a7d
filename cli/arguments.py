"""Command-line arguments of `blender -b -c hc_smooth` and the plan of which file goes where.

No bpy here: parsing and planning are plain Python, so a bad command line fails before Blender
imports anything.
"""

import argparse
import os
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
saved into OUTDIR. Inputs are never overwritten unless --in-place is given; a file that fails leaves
no output behind. Directories given as INPUT stand for the PLY/OBJ/STL/.blend files directly in them.
"""

EPILOG = """\
exit status: 0 when every file was smoothed, 1 when any file failed (the reason is printed),
2 for a bad command line.

examples:
  blender -b -c hc_smooth scans/*.ply -o smoothed/
  blender -b -c hc_smooth scan.obj -o out/ --iterations 20 --alpha 0.2 --beta 0.7 --format ply
  blender -b -c hc_smooth scene.blend --object Scan --fixed-group Keep -o out/
  ls scans/*.ply | xargs -P 4 -n 1 blender -b -c hc_smooth -o smoothed/    (one process per file)
"""


class UsageError(Exception):
    """A bad command line: nothing has been read or written."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # raise instead of sys.exit: the command returns its status to Blender
        raise UsageError(f"{self.prog}: error: {message}")


def _unit_interval(text):
    value = float(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text} is outside [0, 1]")
    return value


def _non_negative_int(text):
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text} is negative")
    return value


def _non_negative_float(text):
    value = float(text)
    if not value >= 0.0:
        raise argparse.ArgumentTypeError(f"{text} is negative")
    return value


def make_parser():
    parser = _Parser(prog="blender -b -c hc_smooth", description=DESCRIPTION, epilog=EPILOG,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("inputs", nargs="+", metavar="INPUT", help="PLY, OBJ, STL or .blend files, or directories")
    where = parser.add_argument_group("where results go")
    where.add_argument("-o", "--output-dir", metavar="OUTDIR", help="folder for the results (created if missing)")
    where.add_argument("--in-place", action="store_true",
                       help="write each result beside its input, replacing the input file")
    where.add_argument("--format", choices=("ply", "obj", "stl"), type=str.lower,
                       help="write mesh files in this format (default: the input's); .blend stays .blend")
    smoothing = parser.add_argument_group("smoothing (as the operator's properties)")
    smoothing.add_argument("--method", choices=METHODS, type=str.upper, default="HC",
                           help="HC (default) or a Laplacian variant")
    smoothing.add_argument("--alpha", type=_unit_interval, default=None,
                           help="pull towards the original (0.1; point clouds: 0.01)")
    smoothing.add_argument("--beta", type=_unit_interval, default=None,
                           help="HC correction weight (0.6; point clouds: 0.55)")
    smoothing.add_argument("--iterations", type=_non_negative_int, default=10, help="iterations (10)")
    smoothing.add_argument("--mode", choices=MODES, type=str.upper, default="SIMULTANEOUS",
                           help="SIMULTANEOUS (default) or SEQUENTIAL")
    smoothing.add_argument("--tolerance", type=_non_negative_float, default=0.0,
                           help="stop early below this move (fraction of the bounding-box diagonal)")
    smoothing.add_argument("--fixed-group", metavar="NAME", default="",
                           help="vertices in this vertex group stay fixed (.blend, OBJ groups)")
    smoothing.add_argument("--invert-group", action="store_true",
                           help="fix everything outside --fixed-group instead (smooth only the group)")
    smoothing.add_argument("--pin-boundary", action="store_true", help="keep open-boundary vertices fixed")
    smoothing.add_argument("--points", action="store_true",
                           help="smooth meshes without edges as point clouds (object.hc_smooth_points)")
    smoothing.add_argument("--object", dest="objects", action="append", default=[], metavar="NAME",
                           help=".blend inputs: smooth this object (repeatable; default: every mesh object)")
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
    settings: Settings
    files: list  # [(input path, output path)]
    points: bool = False
    objects: list = field(default_factory=list)
    given: tuple = ()  # settings given on the command line (the point operator keeps its own defaults else)


def parse(argv):
    """argv (the arguments after `-c hc_smooth`) -> Plan; raises UsageError, or SystemExit(0) for --help."""
    args = make_parser().parse_args(list(argv))
    if args.in_place == bool(args.output_dir):
        raise UsageError("give either -o OUTDIR or --in-place (inputs are never overwritten otherwise)")
    if args.invert_group and not args.fixed_group:
        raise UsageError("--invert-group needs --fixed-group NAME")
    given = tuple(name for name in ("alpha", "beta") if getattr(args, name) is not None)
    settings = Settings(method=args.method, alpha=Settings.alpha if args.alpha is None else args.alpha,
                        beta=Settings.beta if args.beta is None else args.beta, iterations=args.iterations,
                        mode=args.mode, tolerance=args.tolerance, vertex_group=args.fixed_group,
                        invert_vertex_group=args.invert_group, pin_boundary=args.pin_boundary)
    inputs = expand_inputs(args.inputs)
    files = plan_outputs(inputs, args.output_dir, args.format, args.in_place)
    return Plan(settings=settings, files=files, points=args.points, objects=args.objects, given=given)


def expand_inputs(paths):
    """Files as given (any extension: an unsupported one fails that file); directories -> supported files in them."""
    found = []
    for path in paths:
        if os.path.isdir(path):
            entries = sorted(entry.path for entry in os.scandir(path) if entry.is_file()
                             and os.path.splitext(entry.name)[1].lower() in MESH_FORMATS + (BLEND,))
            if not entries:
                raise UsageError(f"{path}: no PLY, OBJ, STL or .blend files in this folder")
            found.extend(entries)
        else:
            found.append(path)
    return found


def output_path(path, output_dir, fmt, in_place):
    stem, ext = os.path.splitext(os.path.basename(path))
    if fmt and ext.lower() in MESH_FORMATS:
        ext = "." + fmt
    folder = os.path.dirname(os.path.abspath(path)) if in_place else os.path.abspath(output_dir)
    return os.path.join(folder, stem + ext)


def plan_outputs(inputs, output_dir, fmt, in_place):
    """[(input, output)], refusing to write one output twice or (without --in-place) over any input."""
    sources = {os.path.realpath(path) for path in inputs}
    plan, taken = [], {}
    for path in inputs:
        target = output_path(path, output_dir, fmt, in_place)
        key = os.path.normcase(os.path.realpath(target))
        if key in taken:
            raise UsageError(f"{path} and {taken[key]} would both be written to {target}: "
                             "smooth them into different folders")
        if not in_place and key in sources:
            raise UsageError(f"{path}: the result would overwrite an input ({target}); "
                             "choose another -o OUTDIR or pass --in-place")
        taken[key] = path
        plan.append((path, target))
    return plan
