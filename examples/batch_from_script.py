"""Run the `hc_smooth` command from a script: the same as `blender -b -c hc_smooth ARGS...`.

    blender -b --python examples/batch_from_script.py -- scans/*.ply -o smoothed/
    python scripts/hc_smooth_bpy.py run examples/batch_from_script.py -- scans/*.ply -o smoothed/

The second line is the same with Blender as a Python module (`pip install bpy`; HC Smooth installed
with `python scripts/hc_smooth_bpy.py install ZIP`, see docs/command_line.md). Useful where a
pipeline already launches Blender with --python. The command's entry function takes the argument
list and returns the exit status (0: every file smoothed, 1: a file failed, 2: usage).
"""

import importlib
import os
import sys

import bpy


def hc_smooth_package():
    """The installed HC Smooth package, bl_ext.<repository>.hc_smooth, enabled if it is not yet:
    Blender enables installed extensions at start-up, the bpy module does not."""
    for name in bpy.context.preferences.addons.keys():
        if name.startswith("bl_ext.") and name.endswith(".hc_smooth"):
            return importlib.import_module(name)
    for repo in bpy.context.preferences.extensions.repos:
        if repo.enabled and os.path.isdir(os.path.join(repo.directory, "hc_smooth")):
            bpy.ops.preferences.addon_enable(module=f"bl_ext.{repo.module}.hc_smooth")
            return importlib.import_module(f"bl_ext.{repo.module}.hc_smooth")
    raise SystemExit(
        f"HC Smooth is not installed in this Blender's user folder ({bpy.utils.resource_path('USER')}): "
        "install the zip (Preferences > Get Extensions > Install from Disk, or "
        "`python scripts/hc_smooth_bpy.py install ZIP` for the bpy module)"
    )


def main():
    command = importlib.import_module(hc_smooth_package().__name__ + ".cli").main
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else ["--help"]
    status = command(args)
    if status:
        sys.exit(status)  # Blender exits with this status after a --python script raises SystemExit


if __name__ == "__main__":
    main()
