"""Object mode with explicit numbers against Blender's Smooth modifier, on a closed triangulated torus: the
Blender half of the speed suite (bench_speed.py runs it in each Blender's Python).

    .envs/bpy45/bin/python bench/run.py speed_blender [--sizes 1M] [--repeats 3]

object.hc_smooth(auto_amount=False, iterations=10) end to end (read, build, smooth, write, report) and the
Smooth modifier (factor 0.5, 10 repeats, evaluated through the depsgraph) on bench_blender.closed_torus
(noise 0.2 % of the diagonal, grid order), the positions put back before each run; medians of --repeats.
"""

import platform

from scripts.extension_session import install_extension  # before bpy

# isort: split

import bpy

from bench.bench_blender import ITERATIONS, closed_torus, restore, smooth_modifier_time
from bench.common import ROOT, median_time, repeats, sizes

PARAMETERS = (sizes("1M"), repeats(3))
QUICK = {"sizes": "5k", "repeats": 1}


def run(args, out):
    install_extension(ROOT / "build" / "bench")
    table = out.table("Blender", "vertices", "object.hc_smooth (s)", "Smooth modifier (s)", "ratio", align="lrrrr")
    for size in args.sizes:
        table.row(bpy.app.version_string, *one_size(size, args.repeats))
    out(f"\n{platform.python_implementation()} {platform.python_version()}, {ITERATIONS} iterations.")
    return out.rows


def one_size(size, repeats):
    """(vertices, HC seconds, Smooth modifier seconds, ratio) as table cells, on a torus of ``size``."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj, original = closed_torus(size, shuffle=False)

    def hc_object():
        assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=ITERATIONS) == {"FINISHED"}

    hc_object()  # warm-up: the first call imports the add-on's modules
    hc = median_time(hc_object, repeats, lambda: restore(obj, original))
    restore(obj, original)
    modifier = smooth_modifier_time(obj, repeats)
    return len(original), f"{hc:.3f}", f"{modifier:.3f}", f"{hc / modifier:.2f}×"
