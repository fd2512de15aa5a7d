"""The benchmark runner: ``python bench/run.py NAME [options]`` runs one benchmark of bench/ and writes its
report to bench/results/ (``--output DIR`` elsewhere); ``python bench/run.py`` lists them;
``python bench/run.py NAME --help`` gives a benchmark's options.

Every benchmark takes ``--quick`` (its smoke run: small sizes, one repeat, written to build/bench-quick/
unless ``--output`` says otherwise) and ``--output``; its own options are declared in its module
(bench/common.py says how). Benchmarks that drive Blender (IN_BLENDER) run in .envs/bpy45 or
.envs/bpy52, the others in .envs/bench (bench/requirements.txt); bench/README.md has the commands.
"""

import argparse
import importlib
import os
import pathlib
import platform
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
# The one place bench/ touches sys.path: the repository root (for `core`, `bench`, `scripts`) instead of
# bench/ itself, so every module of bench/ is imported once, as bench.<name>.
if __name__ == "__main__":
    sys.path[0] = str(ROOT)

from bench import report as reports  # noqa: E402 (after the path above)

# Name on the command line -> module of bench/.
BENCHMARKS = {
    "speed": "bench_speed",
    "speed_blender": "bench_speed_blender",
    "core": "bench_core",
    "blender": "bench_blender",
    "modifier_limits": "bench_modifier_limits",
    "deviation_map": "bench_deviation_map",
    "default_cost": "bench_default_cost",
    "default_heldout": "bench_default_heldout",
    "quality": "bench_quality",
    "amount_limits": "bench_amount_limits",
    "noise_found": "bench_noise_found",
    "keep_in_place": "bench_keep_in_place",
    "primitives": "bench_primitives",
    "borders": "bench_borders",
    "border_rules": "bench_border_rules",
    "sharp_edges": "bench_sharp_edges",
    "points": "bench_points",
    "quality_points": "bench_quality_points",
    "batch": "bench_batch",
    "tiled": "bench_tiled",
}
# The benchmarks that drive Blender: they run in a Python with the bpy module (.envs/bpy45 or .envs/bpy52), the
# others in .envs/bench (bench/requirements.txt).
IN_BLENDER = frozenset({"blender", "modifier_limits", "deviation_map", "speed_blender"})
QUICK_OUTPUT = ROOT / "build" / "bench-quick"
PYTHONS = {"bench": ROOT / ".envs" / "bench" / "bin" / "python", "bpy": ROOT / ".envs" / "bpy45" / "bin" / "python"}


def load(name):
    """The module of benchmark ``name``."""
    if name not in BENCHMARKS:
        raise SystemExit(f"no benchmark {name!r}; the benchmarks: {', '.join(BENCHMARKS)}")
    return importlib.import_module(f"bench.{BENCHMARKS[name]}")


def python_for(name):
    """The interpreter benchmark ``name`` runs in (PYTHONS)."""
    return PYTHONS["bpy" if name in IN_BLENDER else "bench"]


def parser_for(name, module):
    doc = (module.__doc__ or "").strip()
    parser = argparse.ArgumentParser(
        prog=f"bench/run.py {name}", description=doc, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    for parameter in module.PARAMETERS:
        flag = "--" + parameter.name.replace("_", "-")
        if parameter.default is False and parameter.parse is None:
            parser.add_argument(flag, dest=parameter.name, action="store_true", help=parameter.help)
            continue
        parse = parameter.parse or (str if parameter.default is None else type(parameter.default))
        default = parameter.default
        if parameter.parse is not None and default is not None and not isinstance(default, str):
            default = str(default)  # parsed like the text a user types
        parser.add_argument(flag, dest=parameter.name, type=parse, default=default, help=_help(parameter))
    parser.add_argument("--quick", action="store_true", help="the smoke run: small sizes, one repeat, seconds")
    parser.add_argument("--output", type=pathlib.Path, default=None, help="the report's folder (bench/results)")
    return parser


def _help(parameter):
    return f"{parameter.help} (default {parameter.default})" if parameter.help else f"default {parameter.default}"


def parse(name, module, argv):
    parser = parser_for(name, module)
    if "--quick" in argv:
        unknown = set(module.QUICK) - {parameter.name for parameter in module.PARAMETERS}
        if unknown:
            raise SystemExit(f"bench/{module.__name__}: QUICK names unknown parameters {sorted(unknown)}")
        parser.set_defaults(**module.QUICK)  # text is parsed as if typed, other values used as they are
    options = parser.parse_args(argv)
    if options.output is None:
        options.output = QUICK_OUTPUT if options.quick else reports.RESULTS
    return options


def command_line(name, argv):
    return " ".join(["python bench/run.py", name, *argv])


def run(name, argv):
    """Run benchmark ``name`` with command-line arguments ``argv``; returns the report's path."""
    module = load(name)
    options = parse(name, module, argv)
    report_name = module.report_name(options) if hasattr(module, "report_name") else module.__name__.split(".")[-1]
    if name in IN_BLENDER:  # one latest report per Blender
        major, minor = sys.modules["bpy"].app.version[:2]
        report_name += f"_{major}.{minor}"
    with reports.Report(report_name, options.output) as out:
        out(f"`{command_line(name, argv)}`, {time.strftime('%Y-%m-%d %H:%M')}, {machine()}\n")
        out.data = module.run(options, out)
    return out.path


def machine():
    load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    return (
        f"{platform.machine()}, {os.cpu_count()} cores, load average {load} at the start, "
        f"{platform.python_implementation()} {platform.python_version()}"
    )


def main(argv):
    if not argv or argv[0] in ("-h", "--help", "list"):
        print(__doc__)
        for name, module in BENCHMARKS.items():
            print(f"  {name:18s} bench/{module}.py")
        return 0
    run(argv[0], argv[1:])
    return 0


def entry(argv):
    """Run ``main``; a benchmark that drove Blender leaves through extension_session's door (bpy 4.5 can
    hang in its exit handlers)."""
    if argv and argv[0] in IN_BLENDER:
        from scripts.extension_session import run_and_exit

        run_and_exit(lambda: sys.exit(main(argv)))
    sys.exit(main(argv))


if __name__ == "__main__":
    entry(sys.argv[1:])
