"""The documented `python scripts/hc_smooth_bpy.py ...` lines, run as a user types them: in a working
folder that has the repository's scripts/ and examples/ (symlinks), with `python` this suite's Python
(the one with `bpy`), through the shell (globs such as scans/*.ply expand as they would for a user)."""

import os
import pathlib
import re
import shlex
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
ROUTE = "python scripts/hc_smooth_bpy.py"
# Every file that shows the route: the README, the docs, the examples' and the script's docstrings.
DOCUMENTS = (
    ROOT / "README.md",
    ROOT / "docs" / "command_line.md",
    ROOT / "docs" / "install.md",
    ROOT / "docs" / "scripts.md",
    ROOT / "docs" / "python_api.md",
    *sorted((ROOT / "examples").glob("*.py")),
    ROOT / "scripts" / "hc_smooth_bpy.py",
)
INSTALL = f"{ROUTE} install build/hc_smooth-0.1.0.zip"


def documented_lines(path):
    """The command lines of ``path`` (code blocks, docstring usage lines) that use the route."""
    return [
        line.strip()
        for line in path.read_text().splitlines()
        if line.strip().startswith(ROUTE)
        or f"| xargs -0 -P 4 -n 1 {ROUTE}" in line
        or line.strip().startswith(f"parallel -j 4 {ROUTE}")
    ]


def is_syntax(line):
    """A usage pattern (INPUT..., [options], <version>, ZIP) rather than a line to run."""
    return bool(re.search(r"\.\.\.|\[|<|\b(ZIP|INPUT|OUTDIR|FILE|SCRIPT|ARGS)\b", line))


def workdir(folder):
    """``folder`` set up as the repository looks to a user: scripts/ and examples/ in it."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("scripts", "examples"):
        (folder / name).symlink_to(ROOT / name)
    return folder


def run_line(line, cwd, env, timeout=300):
    """Run a documented line exactly as written, `python` being this suite's Python."""
    assert ROUTE in line, line
    command = line.replace(ROUTE, f"{shlex.quote(sys.executable)} scripts/hc_smooth_bpy.py")
    return subprocess.run(command, shell=True, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def user_env(user_folder, **extra):
    """The environment of the suite with HC Smooth's Blender user folder set to ``user_folder``."""
    return {**os.environ, "BLENDER_USER_RESOURCES": str(user_folder), **extra}


def install_documented(extension_zip, base):
    """HC Smooth installed by the documented install line into ``base/user``; returns that folder."""
    assert extension_zip.name == INSTALL.rsplit("/", 1)[1], "the documented zip name follows the manifest version"
    work = workdir(pathlib.Path(base) / "install")
    (work / "build").mkdir()
    (work / "build" / extension_zip.name).symlink_to(extension_zip)
    completed = run_line(INSTALL, work, user_env(pathlib.Path(base) / "user"))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    return pathlib.Path(base) / "user"
