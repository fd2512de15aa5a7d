"""The command line: `blender -b -c hc_smooth INPUT... -o OUTDIR` (see docs/command_line.md).

register() hands ``main`` to Blender's command registry (bpy.utils.register_cli_command, Blender 4.2+),
so the command exists while the extension is enabled. Importing this package loads no Blender module, and
neither does running the command on PLY, OBJ and STL files: ``arguments`` (the command line and the plan
of which file goes where), ``command`` (the run, its progress and summary) and ``file_route`` are plain
Python with NumPy and SciPy (scripts/hc_smooth_files.py runs them without Blender); only ``blend``
(.blend files) imports bpy.
"""

COMMAND = "hc_smooth"
_handle = None


def main(argv, prog=None):
    """Run the command on ``argv`` (the arguments after `-c hc_smooth`); returns the exit status.
    ``prog`` names the command in usage messages (default: `blender -b -c hc_smooth`)."""
    from .command import main as run

    return run(argv) if prog is None else run(argv, prog=prog)


def register():
    import bpy

    from . import arguments, blend, command  # noqa: F401  (loaded with the add-on, as its other modules)

    global _handle
    _handle = bpy.utils.register_cli_command(COMMAND, main)


def unregister():
    import bpy

    global _handle
    if _handle is not None:
        bpy.utils.unregister_cli_command(_handle)
        _handle = None
