"""The suite writes nothing into the home folder and leaves nothing in the temporary folder: this
process and every kind of subprocess the tests start (the bpy route, the demo, the extension build)
use a temporary Blender user folder and cache. Each subprocess runs with HOME and TMPDIR pointed at
empty folders, which must stay empty (no ~/.config/blender, no ~/.cache/thumbnails, no Blender
session folder)."""

import os
import pathlib
import subprocess
import sys

import bpy
from bpy_route import ROOT, ROUTE, run_line, workdir

SESSION_USER_FOLDER = pathlib.Path(os.environ["BLENDER_USER_RESOURCES"])  # set by conftest.py before bpy


def isolated_env(tmp_path):
    """The environment the tests give their subprocesses, with HOME and TMPDIR in ``tmp_path``."""
    for name in ("home", "tmp"):
        (tmp_path / name).mkdir()
    return {**os.environ, "HOME": str(tmp_path / "home"), "TMPDIR": str(tmp_path / "tmp")}


def assert_left_alone(tmp_path):
    assert os.listdir(tmp_path / "home") == []
    assert os.listdir(tmp_path / "tmp") == []


def snapshot(folder):
    return {str(path.relative_to(folder)): path.stat().st_mtime_ns for path in folder.rglob("*") if path.is_file()}


def test_this_process_uses_the_temporary_user_folder():
    user = pathlib.Path(bpy.utils.resource_path("USER")).resolve()
    assert user == SESSION_USER_FOLDER.resolve()
    assert pathlib.Path.home() not in user.parents


def test_the_route_leaves_home_alone(addon, tmp_path):
    env = isolated_env(tmp_path)
    completed = run_line(f"{ROUTE} run examples/smooth_with_operators.py", workdir(tmp_path / "work"), env)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert_left_alone(tmp_path)


def test_the_demo_leaves_home_and_the_sessions_user_folder_alone(addon, tmp_path):
    env = isolated_env(tmp_path)
    before = snapshot(SESSION_USER_FOLDER)
    run = subprocess.run(
        [
            sys.executable,
            str(ROOT / "demo" / "demo.py"),
            "--no-render",
            "--iterations",
            "1",
            "--output-dir",
            str(tmp_path / "out"),
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    # Its own user folder is a fresh one, removed at its end, not the inherited one where this session's
    # add-on is loaded; the zip it installed is not left behind either.
    assert_left_alone(tmp_path)
    assert snapshot(SESSION_USER_FOLDER) == before
    assert not (tmp_path / "out" / "build").exists()


def test_building_the_extension_leaves_home_alone(tmp_path):
    env = isolated_env(tmp_path)
    subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "build_extension.py"), "--output-dir", str(tmp_path / "build")],
        env=env,
        check=True,
        capture_output=True,
        timeout=120,
    )
    assert_left_alone(tmp_path)
