"""Command-line arguments of `blender -b -c hc_smooth` and the plan of which file goes where.

No bpy here: parsing and planning are plain Python, so a bad command line fails before Blender
imports anything.
"""

import argparse
import math
import os
import textwrap
from dataclasses import dataclass, field

from .. import settings_spec

PROG = "blender -b -c hc_smooth"
MESH_FORMATS = (".ply", ".obj", ".stl")
BLEND = ".blend"

# Command-line option (argparse dest) -> setting, from the declarations' flags.
MESH_OPTIONS = {s.flag.replace("-", "_"): s for s in settings_spec.MESH if s.flag}
POINT_OPTIONS = {s.flag.replace("-", "_"): s for s in settings_spec.POINTS if s.flag}
# Command-line name -> PointSettings field.
POINT_FIELDS = {name: setting.name for name, setting in POINT_OPTIONS.items()}
POINT_ONLY = tuple(name for name in POINT_OPTIONS if name not in MESH_OPTIONS)


def _kept_with_points(setting):
    """The value a mesh-only option may keep with --points: what point clouds run anyway (its points_keep),
    else only its value when not given (add_setting: a switch False, a name its default, others None)."""
    if setting.points_keep is None and setting.kind in ("bool", "string"):
        return setting.default
    return setting.points_keep


# Mesh-only options (mesh flags point clouds lack) -> the value each may keep with --points.
MESH_ONLY = {name: _kept_with_points(s) for name, s in MESH_OPTIONS.items() if name not in POINT_OPTIONS}


# Options that mean nothing without another (the panels grey them out): (option, the option it needs).
NEEDS = (
    ("invert_group", "fixed_group"),
    ("invert_influence", "influence_group"),
    ("sharpness_angle", "keep_sharp_edges"),
)


def _option(name):
    return "--" + name.replace("_", "-")


def _listed(names):
    """'--a, --b and --c'"""
    options = [_option(name) for name in names]
    return ", ".join(options[:-1]) + " and " + options[-1]


DESCRIPTION = """\
Smooth scanned meshes without shrinking them (HC algorithm, Vollmer, Mencl, Mueller 1999).
Reads PLY, OBJ and STL files, smooths every mesh with the same code as the Object > HC Smooth
operator, and writes the result in the same format (or --format) into OUTDIR. A result is its input
with the vertex positions (and the normals the file has) replaced; every other value, the header, the
comments and the encoding stay as they were, and an OBJ's .mtl is neither read nor written. A .blend
input is opened, its mesh objects (or those named with --object) are smoothed and a copy is saved
into OUTDIR. Directories given as INPUT stand for the PLY/OBJ/STL/.blend files directly in them
(hidden files skipped); a file named twice is smoothed once. A file that fails leaves no output behind.

Existing files are never replaced, except the input itself with --in-place (same path, same format;
a symbolic link stays a link and its target is replaced) and, with --overwrite, existing results.
--in-place with --format writes a new file beside the input and keeps the input. Everything is
checked before anything runs. Ctrl+C stops the run: the file being written is left as it was.

"""
DESCRIPTION += (
    textwrap.fill(
        f"--points smooths point clouds (meshes without edges) with the Object > HC Smooth Points code. They take "
        f"{_listed(POINT_OPTIONS)}; the mesh-only options ({', '.join(map(_option, MESH_ONLY))}) are refused with "
        "--points, and the point options without it.",
        width=100,
        break_on_hyphens=False,
    )
    + "\n"
)

EPILOG = """\
exit status: 0 when every file was smoothed, 1 when any file failed (the reason is printed),
2 for a bad command line (nothing is read or written), 130 when interrupted (Ctrl+C).

examples:
  blender -b -c hc_smooth scans/*.ply -o smoothed/
  blender -b -c hc_smooth scan.obj -o out/ --iterations 20 --alpha 0.2 --beta 0.7 --format ply
  blender -b -c hc_smooth scene.blend --object Scan --fixed-group Keep -o out/
  blender -b -c hc_smooth points.ply --points --rounds 4 -o out/
  blender -b -c hc_smooth scans/ -o smoothed/ --jobs 4                      (4 worker processes, Dask)
  blender -b -c hc_smooth scans/ -o smoothed/ --scheduler tcp://host:8786    (a Dask cluster's workers)
"""


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


SIZE_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def _size(text):
    """'4G', '500M', '4GB', '1.5g', '1000000' (bytes) -> bytes."""
    number = text.strip().upper().removesuffix("B")
    unit = number[-1:] if number[-1:] in SIZE_UNITS and number[-1:] else ""
    try:
        value = float(number[: len(number) - len(unit)]) * SIZE_UNITS[unit]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text} is not a size (e.g. 4G, 500M)") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text} is not a positive size")
    return int(value)


_size.__name__ = "size"


def _shown(setting):
    """What one unit of the setting is on the command line: an angle (stored in radians, as Blender's
    angle properties are) is given in degrees."""
    return 180.0 / math.pi if setting.subtype == "ANGLE" else 1.0


def _checked(setting):
    """The argparse type of a number setting: its declared limits, refused with a message saying which.
    Angles are given in degrees and returned in radians."""
    scale = _shown(setting)
    low = None if setting.min is None else round(setting.min * scale, 9)
    high = None if setting.max is None else round(setting.max * scale, 9)

    def parse(text):
        value = int(text) if setting.kind == "int" else _number(text)
        if low is not None and high is not None and not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{text} is outside [{low:g}, {high:g}]")
        if low is not None and value < low:
            raise argparse.ArgumentTypeError(f"{text} is negative" if low == 0 else f"{text} is below {low:g}")
        if high is not None and value > high:
            raise argparse.ArgumentTypeError(f"{text} is above {high:g}")
        return math.radians(value) if scale != 1.0 else value

    parse.__name__ = "whole number" if setting.kind == "int" else "number"  # argparse: "invalid ... value"
    return parse


def _default_text(setting):
    value = f"{setting.default * _shown(setting):g}" if setting.kind == "float" else str(setting.default)
    return setting.cli_default.format(default=value) if setting.cli_default else value


def setting_help(setting, point=None, mesh_only=False):
    """The declared help with the declared default (and the point operator's, for a shared option)."""
    defaults = [_default_text(setting)] if setting.kind not in ("bool", "string") else []
    if point is not None and defaults and (point.default != setting.default or point.cli_default):
        defaults.append("point clouds: " + _default_text(point))
    return setting.help + (f" ({'; '.join(defaults)})" if defaults else "") + ("; meshes only" if mesh_only else "")


def add_setting(group, setting, text):
    """An option for a declared setting, with help ``text``. Values default to None ("not given"), so the
    operator's default applies and --points can tell which options were given."""
    options = {"help": text}
    if setting.kind == "bool":  # a switch names the change from the default: a setting on by default switches off
        options["action"] = "store_false" if setting.default else "store_true"
    elif setting.kind == "string":
        options.update(default=setting.default, metavar=setting.metavar)
    elif setting.kind == "enum":
        options.update(choices=setting.identifiers, type=str.upper, default=None)
    else:
        options.update(type=_checked(setting), default=None, metavar=setting.metavar)
    group.add_argument(_option(setting.flag), **options)


def _count(text):
    """A whole number of at least 1 (--jobs)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text} is below 1")
    return value


def make_parser(prog=PROG):
    parser = _Parser(
        prog=prog,
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("inputs", nargs="+", metavar="INPUT", help="PLY, OBJ, STL or .blend files, or directories")
    where = parser.add_argument_group("where results go")
    where.add_argument("-o", "--output-dir", metavar="OUTDIR", help="folder for the results (created if missing)")
    where.add_argument(
        "--in-place",
        action="store_true",
        help="write each result beside its input, replacing the input file (with --format: a new "
        "file beside the input, which is kept)",
    )
    where.add_argument(
        "--format",
        choices=("ply", "obj", "stl"),
        type=str.lower,
        help="write mesh files in this format (default: the input's); .blend stays .blend",
    )
    where.add_argument(
        "--overwrite",
        action="store_true",
        help="replace results that already exist; without it an existing file that is not the input "
        "of --in-place stops the run before it starts",
    )
    where.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="say when each file starts being read, smoothed and written",
    )
    large = parser.add_argument_group("scans larger than memory")
    large.add_argument(
        "--memory-limit",
        type=_size,
        metavar="SIZE",
        help="the most memory a file's run may take, e.g. 4G or 500M (default: 3/4 of the machine's; with --jobs "
        "or --scheduler, each worker's); a binary PLY or OBJ file whose whole run would take more is smoothed in "
        "tiles, on the workers with --jobs or --scheduler (docs/large_scans.md)",
    )
    batch = parser.add_argument_group('many files at once (Dask: python -m pip install "dask[distributed]")')
    batch.add_argument(
        "--jobs",
        type=_count,
        default=1,
        metavar="N",
        help="smooth PLY, OBJ and STL files in N worker processes on this machine (default 1: one at a time, "
        "here); .blend files run here, one at a time",
    )
    batch.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default="",
        help="send PLY, OBJ and STL files to the workers of the Dask scheduler at ADDRESS "
        "(tcp://host:8786); they need HC Smooth, the inputs and the output folder at the same paths",
    )
    smoothing = parser.add_argument_group("smoothing (as the operators' properties)")
    for name, setting in MESH_OPTIONS.items():
        add_setting(smoothing, setting, setting_help(setting, POINT_OPTIONS.get(name), name not in POINT_OPTIONS))
    smoothing.add_argument(
        "--object",
        dest="objects",
        action="append",
        default=[],
        metavar="NAME",
        help=".blend inputs: smooth this object (repeatable; default: every mesh object, with "
        "--points every point cloud)",
    )
    points = parser.add_argument_group("point clouds (as Object > HC Smooth Points)")
    points.add_argument(
        "--points",
        action="store_true",
        help="smooth point clouds (meshes without edges; .blend: also point cloud objects) instead of meshes",
    )
    for name in POINT_ONLY:
        add_setting(points, POINT_OPTIONS[name], setting_help(POINT_OPTIONS[name]))
    return parser


Settings = settings_spec.settings_class(
    "Settings",
    settings_spec.MESH,
    "The operator properties jobs.make_job/run/write read, filled from the command line.",
)


@dataclass
class Plan:
    settings: Settings  # the mesh settings (unused with --points)
    files: list  # [(input path, output path)]
    given: frozenset = frozenset()  # the mesh settings given on the command line (the rest are defaults)
    points: bool = False
    point_options: dict = field(default_factory=dict)  # PointSettings fields given on the command line
    objects: list = field(default_factory=list)
    notes: list = field(default_factory=list)  # said before the run (an input named twice)
    verbose: bool = False
    memory_limit: int | None = None  # bytes, --memory-limit (None: cli/tiled.py's default)
    jobs: int = 1  # worker processes on this machine (--jobs); 1: the files run here, one at a time
    scheduler: str = ""  # the Dask scheduler whose workers run the files (--scheduler)

    @property
    def batch(self):
        """Whether the files go to workers (cli/batch.py)."""
        return self.jobs > 1 or bool(self.scheduler)


UNATTENDED = "it runs unattended, and a mistyped count must not keep it going without end"


def _check_step_counts(args):
    """Refuse more HC steps than settings_spec.COMMAND_MAX_ITERATIONS: --iterations, or for point clouds
    --rounds times --steps-per-round (chosen from the noise when not given: at least one a round)."""
    most = settings_spec.COMMAND_MAX_ITERATIONS
    why = f"the most the command line runs (as the HC Smooth modifier): {UNATTENDED}"
    if args.iterations is not None and args.iterations > most:
        raise UsageError(f"--iterations {args.iterations} is above {most}, {why}")
    if not args.points:
        return  # --rounds and --steps-per-round without --points are refused with their own message
    rounds = settings_spec.ROUNDS.default if args.rounds is None else args.rounds
    steps = 1 if args.steps_per_round is None else args.steps_per_round
    if rounds * steps <= most:
        return
    if args.steps_per_round is None:
        counts = f"--rounds {rounds} (at least one step each)"
    else:
        with_rounds = f"the default {rounds} rounds" if args.rounds is None else f"--rounds {rounds}"
        counts = f"--steps-per-round {steps} with {with_rounds}"
    raise UsageError(f"{counts} makes {rounds * steps} HC steps, above {most}, {why}")


def parse(argv, prog=PROG):
    """argv (the arguments after `-c hc_smooth`) -> Plan; raises UsageError, or SystemExit(0) for --help.

    Reads the file system (which inputs and outputs exist) but changes nothing on it. ``prog`` names
    the command in messages."""
    args = make_parser(prog).parse_args(list(argv))
    if args.jobs > 1 and args.scheduler:
        raise UsageError("give either --jobs N (workers on this machine) or --scheduler ADDRESS (a cluster's)")
    if args.in_place == bool(args.output_dir):
        raise UsageError("give either -o OUTDIR or --in-place (inputs are never overwritten otherwise)")
    for option, needed in NEEDS:
        if getattr(args, option) not in (None, False) and not getattr(args, needed):
            metavar = MESH_OPTIONS[needed].metavar
            raise UsageError(f"{_option(option)} needs {_option(needed)}{f' {metavar}' if metavar else ''}")
    _check_step_counts(args)
    if args.points:
        refused = [_option(name) for name, keeps in MESH_ONLY.items() if getattr(args, name) not in (None, keeps)]
        if refused:
            raise UsageError(
                f"{', '.join(refused)} {'does' if len(refused) == 1 else 'do'} not apply to point "
                f"clouds (--points): they take {_listed(POINT_OPTIONS)}"
            )
    else:
        given = [_option(name) for name in POINT_ONLY if getattr(args, name) is not None]
        if given:
            raise UsageError(
                f"{', '.join(given)} {'applies' if len(given) == 1 else 'apply'} to point clouds only: add --points"
            )
    settings = Settings(
        **{
            setting.name: getattr(args, name)
            for name, setting in MESH_OPTIONS.items()
            if getattr(args, name) is not None
        }
    )
    given = frozenset(setting.name for name, setting in MESH_OPTIONS.items() if getattr(args, name) is not None)
    values = settings_spec.values_of(settings, settings_spec.MESH)
    if settings_spec.automatic(values) and not settings_spec.automatic(values, given):
        settings.auto_amount = False  # as the operator: Alpha or Iterations given run every number as set
    point_options = {
        POINT_FIELDS[name]: getattr(args, name) for name in POINT_FIELDS if getattr(args, name) is not None
    }
    points = settings_spec.values_of(settings_spec.PointSettings(**point_options), settings_spec.POINTS)
    if settings_spec.automatic(points) and not settings_spec.automatic(points, point_options):
        point_options["auto_amount"] = False  # as the operator: Alpha or Steps per Round given run them as set
    if args.points:
        from ..core import reach_gap_problem  # the rule and its words, once

        reach = point_options.get("spacing_factor", settings_spec.SPACING_FACTOR.default)
        gap = point_options.get("gap_factor", settings_spec.GAP_FACTOR.default)
        problem = reach_gap_problem(reach, gap, ("--reach", "--gap"))
        if problem:
            raise UsageError(problem)
    inputs, notes = expand_inputs(args.inputs)
    if args.objects and not any(os.path.splitext(path)[1].lower() == BLEND for path in inputs):
        raise UsageError(
            "--object names objects inside .blend files, and no input is a .blend file "
            "(PLY, OBJ and STL inputs are smoothed whole)"
        )
    if args.output_dir:
        check_output_dir(args.output_dir)
    files = plan_outputs(inputs, args.output_dir, args.format, args.in_place, args.overwrite)
    if settings.deviation_map:
        check_deviation_targets(files)
    return Plan(
        settings=settings,
        given=given,
        files=files,
        points=args.points,
        point_options=point_options,
        objects=args.objects,
        notes=notes,
        verbose=args.verbose,
        memory_limit=args.memory_limit,
        jobs=args.jobs,
        scheduler=args.scheduler,
    )


HOLDS_DEVIATION = (".ply", BLEND)  # the formats with a place for a value per vertex


def check_deviation_targets(files):
    """Refuse --deviation-attribute where a result's format cannot hold the attribute (OBJ, STL)."""
    refused = [target for _, target in files if os.path.splitext(target)[1].lower() not in HOLDS_DEVIATION]
    if refused:
        names = "".join(f"\n  {name}" for name in refused)
        raise UsageError(
            "--deviation-attribute stores a value per vertex, which only PLY and .blend files hold; these "
            f"results would be OBJ or STL:{names}\nwrite them as PLY with --format ply (nothing was read or written)"
        )


def _key(path):
    return os.path.normcase(os.path.realpath(path))


def expand_inputs(paths):
    """-> (files, notes). Files as given (any extension: an unsupported one fails that file); directories ->
    the supported files directly in them, hidden ones skipped (._* metadata, temporaries of a killed run).
    A file named twice (also through a folder, a ./ or a link) is kept once, with a note."""
    found, notes, first = [], [], {}
    for path in paths:
        if os.path.isdir(path):
            entries = sorted(
                entry.path
                for entry in os.scandir(path)
                if entry.is_file()
                and not entry.name.startswith(".")
                and os.path.splitext(entry.name)[1].lower() in MESH_FORMATS + (BLEND,)
            )
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


def check_output_dir(output_dir):
    """Refuse an OUTDIR that is (or lies under) a file: found here, before any input is read."""
    path = os.path.abspath(output_dir)
    while not os.path.lexists(path) and os.path.dirname(path) != path:
        path = os.path.dirname(path)
    if not os.path.isdir(path):
        where = "is" if path == os.path.abspath(output_dir) else f"lies under {path}, which is"
        raise UsageError(f"-o {output_dir}: the output folder {where} a file, not a folder")


def output_path(path, output_dir, fmt, in_place):
    stem, ext = os.path.splitext(os.path.basename(path))
    if fmt and ext.lower() in MESH_FORMATS:
        ext = "." + fmt
    if in_place and ext == os.path.splitext(path)[1] and os.path.islink(path):
        return os.path.realpath(path)  # the input itself, through the link: the link stays a link
    folder = os.path.dirname(os.path.abspath(path)) if in_place else os.path.abspath(output_dir)
    return os.path.join(folder, stem + ext)


def plan_outputs(inputs, output_dir, fmt, in_place, overwrite=False):
    """[(input, output)], refusing to write one output twice, over any input (without --in-place), or over
    any existing file that is not the input replaced in place (without --overwrite)."""
    sources = {_key(path) for path in inputs}
    plan, taken, existing = [], {}, []
    for path in inputs:
        target = output_path(path, output_dir, fmt, in_place)
        key = _key(target)
        if key in taken:
            raise UsageError(
                f"{path} and {taken[key]} would both be written to {target}: smooth them into different folders"
            )
        same = key == _key(path)
        if key in sources and not (in_place and same):
            raise UsageError(
                f"{path}: the result would overwrite an input ({target}); "
                + (
                    "choose another -o OUTDIR or pass --in-place"
                    if not in_place
                    else "smooth it into a folder with -o OUTDIR"
                )
            )
        taken[key] = path
        plan.append((path, target))
        if overwrite:
            continue
        if os.path.lexists(target) and not (in_place and same):
            existing.append(target)
    if existing:
        names = "".join(f"\n  {name}" for name in existing)
        where = "move them away or smooth into a folder with -o OUTDIR" if in_place else "choose another -o OUTDIR"
        raise UsageError(
            f"these files exist and would be replaced:{names}\n{where}, or pass --overwrite to replace "
            "them (nothing was read or written)"
        )
    return plan
