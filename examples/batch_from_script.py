"""Run the `hc_smooth` command from a script: the same as `blender -b -c hc_smooth ARGS...`.

    blender -b --python examples/batch_from_script.py -- scans/*.ply -o smoothed/

Useful where a pipeline already launches Blender with --python. The command's entry function takes
the argument list and returns the exit status (0: every file smoothed, 1: a file failed, 2: usage).
"""

import importlib
import sys

import bpy


def main():
    name = next(name for name in bpy.context.preferences.addons.keys()
                if name.startswith("bl_ext.") and name.endswith(".hc_smooth"))
    command = importlib.import_module(name + ".cli").main
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else ["--help"]
    status = command(args)
    if status:
        sys.exit(status)  # Blender exits with this status after a --python script raises SystemExit


if __name__ == "__main__":
    main()
