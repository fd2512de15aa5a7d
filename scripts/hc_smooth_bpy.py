"""HC Smooth with Blender as a Python module (`pip install bpy`), the way `blender -b` runs it.

Run it with a Python that has the `bpy` module (and, for the plain zip of `make build`, SciPy):

    python scripts/hc_smooth_bpy.py install build/hc_smooth-0.1.0.zip
    python scripts/hc_smooth_bpy.py hc_smooth scans/*.ply -o smoothed/
    python scripts/hc_smooth_bpy.py run examples/smooth_with_operators.py
    python scripts/hc_smooth_bpy.py run scene.blend examples/smooth_with_operators.py -- Scan smoothed.blend

  install ZIP                               install (or replace) and enable the extension zip
  hc_smooth ARGS...                         as `blender -b -c hc_smooth ARGS...`
  run [FILE.blend] SCRIPT.py [-- ARGS...]   as `blender -b [FILE.blend] --python SCRIPT.py [-- ARGS...]`,
                                            with HC Smooth enabled; the script reads ARGS after `--`

Blender user folder (where the extension is installed; Blender's BLENDER_USER_RESOURCES), first of:
  --user-folder DIR                         before the subcommand
  $BLENDER_USER_RESOURCES
  $XDG_DATA_HOME/hc_smooth/bpy-X.Y          (~/.local/share/..., %LOCALAPPDATA%\\hc_smooth\\bpy-X.Y on Windows;
                                            X.Y: the bpy version) -- never Blender's own ~/.config/blender
                                            unless you name it with --user-folder

Exit status: the command's (0 all smoothed, 1 a file failed, 2 usage), the script's `sys.exit` code
(1 when it raises), 1 when HC Smooth is not installed in the user folder, 2 for a bad command line.
This file needs only `bpy`: copy it wherever a pipeline needs it.
"""

import contextlib
import os
import pathlib
import sys

ADDON = "hc_smooth"  # the extension id of blender_manifest.toml
SELF = sys.argv[0]  # for messages: `run` hands sys.argv to the script


def default_user_folder():
    """A folder of its own per bpy version, so installing here never touches a desktop Blender's."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        bpy_version = ".".join(version("bpy").split(".")[:2])
    except PackageNotFoundError:
        bpy_version = "unknown"
    if os.name == "nt":
        base = os.environ.get("LOCALAPPDATA") or os.path.expanduser(r"~\AppData\Local")
    else:
        base = os.environ.get("XDG_DATA_HOME") or os.path.expanduser("~/.local/share")
    return os.path.join(base, "hc_smooth", f"bpy-{bpy_version}")


class UsageError(Exception):
    """A bad command line: exit status 2, nothing done."""


def parse(argv):
    """(user folder or None, subcommand, its arguments)."""
    folder = None
    if argv[:1] == ["--user-folder"]:
        if len(argv) < 2:
            raise UsageError("--user-folder needs a folder")
        folder, argv = argv[1], argv[2:]
    elif argv[:1] and argv[0].startswith("--user-folder="):
        folder, argv = argv[0].split("=", 1)[1], argv[1:]
    if not argv or argv[0] not in ("install", "hc_smooth", "run"):
        raise UsageError("give a subcommand: install, hc_smooth or run")
    return folder, argv[0], argv[1:]


def installed_module(bpy):
    """The add-on module of HC Smooth in any extension repository of the user folder, or None."""
    for repo in bpy.context.preferences.extensions.repos:
        if repo.enabled and os.path.isdir(os.path.join(repo.directory, ADDON)):
            return f"bl_ext.{repo.module}.{ADDON}"
    return None


def enable(bpy):
    """Enable the installed HC Smooth: Blender does that at start-up from its saved preferences,
    the bpy module does not. Returns the module name; exits with a message when it is not installed."""
    module = installed_module(bpy)
    if module is None:
        raise SystemExit(
            f"hc_smooth_bpy: HC Smooth is not installed in the Blender user folder "
            f"{os.environ['BLENDER_USER_RESOURCES']}: install it first with\n"
            f"  python {SELF} install hc_smooth-<version>.zip"
        )
    if module not in bpy.context.preferences.addons:
        try:
            with silenced():  # Blender prints a failed add-on's traceback; its cause is said below
                bpy.ops.preferences.addon_enable(module=module)
        except RuntimeError as error:
            text = str(error)
            reason = text.rsplit("cause: ", 1)[-1] if "cause: " in text else text.strip().splitlines()[-1]
            raise SystemExit(f"hc_smooth_bpy: HC Smooth could not be enabled: {reason.strip()}") from None
    return module


@contextlib.contextmanager
def silenced():
    """Descriptors 1 and 2 (where Blender's C code prints) to nothing while the block runs."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


def install(bpy, args):
    if len(args) != 1 or not args[0].endswith(".zip"):
        raise UsageError("install takes one extension zip")
    zip_path = os.path.abspath(args[0])
    if not os.path.isfile(zip_path):
        raise UsageError(f"{args[0]} does not exist (build it with `make build` or `make dist`)")
    result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
    module = f"bl_ext.user_default.{ADDON}"
    if result != {"FINISHED"} or module not in bpy.context.preferences.addons:
        raise SystemExit(f"hc_smooth_bpy: installing {zip_path} failed ({result})")
    print(f"hc_smooth_bpy: installed {os.path.basename(zip_path)} into {os.environ['BLENDER_USER_RESOURCES']}")
    return 0


def command(bpy, args):
    return sys.modules[enable(bpy) + ".cli"].main(args, prog=f"{os.path.basename(SELF)} hc_smooth")


def run(bpy, args):
    blend = args.pop(0) if args and args[0].endswith(".blend") else None
    if not args or args[0] == "--" or (len(args) > 1 and args[1] != "--"):
        raise UsageError("usage: run [FILE.blend] SCRIPT.py [-- ARGS...]")
    script = args[0]
    if not os.path.isfile(script):
        raise UsageError(f"no script {script}")
    if blend is not None and not os.path.isfile(blend):
        raise UsageError(f"no file {blend}")
    enable(bpy)
    if blend is not None:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(blend))
    # The script sees what Blender gives a --python script: its arguments after "--".
    sys.argv = [script, *args[1:]]
    import runpy

    runpy.run_path(script, run_name="__main__")  # its SystemExit is main's exit status
    return 0


def main(argv):
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return 0
    try:
        folder, subcommand, args = parse(argv)
    except UsageError as error:
        print(f"{__doc__}\nhc_smooth_bpy: {error}", file=sys.stderr)
        return 2
    # Blender reads its user folder once, when bpy is imported.
    folder = folder or os.environ.get("BLENDER_USER_RESOURCES") or default_user_folder()
    pathlib.Path(folder).mkdir(parents=True, exist_ok=True)
    os.environ["BLENDER_USER_RESOURCES"] = os.path.abspath(folder)
    import bpy

    try:
        return {"install": install, "hc_smooth": command, "run": run}[subcommand](bpy, args)
    except UsageError as error:
        print(f"hc_smooth_bpy: {error}", file=sys.stderr)
        return 2
    except SystemExit as exit_:
        if exit_.code is None or isinstance(exit_.code, int):
            return exit_.code or 0
        print(exit_.code, file=sys.stderr)
        return 1
    except Exception:  # noqa: BLE001 - a script's error: its trace, then exit status 1
        import traceback

        traceback.print_exc()
        return 1


if __name__ == "__main__":
    status = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    if "bpy" in sys.modules:  # Blender removes its session temp folder at exit, which os._exit skips
        import shutil

        shutil.rmtree(sys.modules["bpy"].app.tempdir, ignore_errors=True)
    os._exit(status)  # bpy 4.5 can deadlock in C exit handlers (see tests/conftest.py)
