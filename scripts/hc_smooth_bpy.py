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
  --user-folder DIR                         anywhere before a `--`
  $BLENDER_USER_RESOURCES
  $XDG_DATA_HOME/hc_smooth/bpy-X.Y          (~/.local/share/..., %LOCALAPPDATA%\\hc_smooth\\bpy-X.Y on Windows;
                                            X.Y: the bpy version) -- never Blender's own ~/.config/blender
                                            unless you name it with --user-folder

Exit status: the command's (0 all smoothed, 1 a file failed, 2 usage), the script's `sys.exit` code
(1 when it raises), 1 when HC Smooth is not installed in the user folder or this Python has no `bpy`,
2 for a bad command line. A bad command line or a missing `bpy` changes nothing (no user folder made).
This file needs only `bpy`: copy it wherever a pipeline needs it. PLY, OBJ and STL files smooth without
Blender too: `python scripts/hc_smooth_files.py` (docs/command_line.md).
"""

import contextlib
import importlib.util
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
    """(user folder or None, subcommand, its arguments), the subcommand's arguments checked (``check``)."""
    end = argv.index("--") if "--" in argv else len(argv)  # what follows `--` is the script's
    folders, rest, index = [], [], 0
    while index < end:
        word = argv[index]
        if word == "--user-folder":
            if index + 1 >= end:
                raise UsageError("--user-folder needs a folder")
            folders.append(argv[index + 1])
            index += 2
            continue
        if word.startswith("--user-folder="):
            folders.append(word.split("=", 1)[1])
        else:
            rest.append(word)
        index += 1
    if len(folders) > 1:
        raise UsageError("give --user-folder once")
    rest += argv[end:]
    if not rest or rest[0] not in ("install", "hc_smooth", "run"):
        raise UsageError("give a subcommand: install, hc_smooth or run")
    check(rest[0], rest[1:])
    return (folders[0] if folders else None), rest[0], rest[1:]


def check(subcommand, args):
    """Raise UsageError for arguments ``subcommand`` cannot take (before anything is made or imported)."""
    if subcommand == "install":
        if len(args) != 1 or not args[0].endswith(".zip"):
            given = f" (given: {' '.join(args)})" if args else ""
            raise UsageError(f"install takes one extension zip: install [--user-folder DIR] ZIP{given}")
        if not os.path.isfile(args[0]):
            raise UsageError(f"{args[0]} does not exist (build it with `make build` or `make dist`)")
    elif subcommand == "run":
        rest = list(args)
        blend = rest.pop(0) if rest and rest[0].endswith(".blend") else None
        if not rest or rest[0] == "--" or (len(rest) > 1 and rest[1] != "--"):
            raise UsageError("usage: run [FILE.blend] SCRIPT.py [-- ARGS...]")
        if not os.path.isfile(rest[0]):
            raise UsageError(f"no script {rest[0]}")
        if blend is not None and not os.path.isfile(blend):
            raise UsageError(f"no file {blend}")


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
    zip_path = os.path.abspath(args[0])
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
    script = args[0]  # checked by ``check``
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
    if importlib.util.find_spec("bpy") is None:
        print(
            f"hc_smooth_bpy: this Python ({sys.executable}) has no bpy module: install Blender's "
            "(python -m pip install bpy: bpy 4.5 needs Python 3.11, bpy 5.2 Python 3.13), or smooth PLY, "
            "OBJ and STL files without Blender: python scripts/hc_smooth_files.py INPUT... -o OUTDIR",
            file=sys.stderr,
        )
        return 1
    # Blender reads its user folder once, when bpy is imported; an install makes it, and removes what it
    # made if the install fails.
    folder = os.path.abspath(folder or os.environ.get("BLENDER_USER_RESOURCES") or default_user_folder())
    os.environ["BLENDER_USER_RESOURCES"] = folder
    made = made_folders(folder) if subcommand == "install" else []
    try:
        status = dispatch(subcommand, args)
    except BaseException:
        remove_made(made)
        raise
    if status:
        remove_made(made)
    return status


def made_folders(folder):
    """Make ``folder`` (and missing parents); returns those it made, deepest first."""
    made, path = [], folder
    while not os.path.isdir(path) and os.path.dirname(path) != path:
        made.append(path)
        path = os.path.dirname(path)
    pathlib.Path(folder).mkdir(parents=True, exist_ok=True)
    return made


def remove_made(made):
    """Remove the folders ``made_folders`` made, with what a failed install left in them."""
    import shutil

    if made:
        shutil.rmtree(made[0], ignore_errors=True)
    for path in made[1:]:
        with contextlib.suppress(OSError):
            os.rmdir(path)  # only if empty: something else may have landed there meanwhile


def dispatch(subcommand, args):
    """Run ``subcommand`` with bpy; returns the exit status."""
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
