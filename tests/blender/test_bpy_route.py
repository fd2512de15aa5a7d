"""HC Smooth with Blender as a Python module: `scripts/hc_smooth_bpy.py install` and `hc_smooth`, run as
subprocesses exactly as the README and docs/command_line.md write them; every documented line of the
route is run by some test, and every `blender` line of the docs has the route's line beside it."""

import importlib.metadata
import os
import re
import subprocess
import sys

import bpy
import pytest
from blender_scene import noisy_sphere, select_only
from bpy_route import (
    DOCUMENTS,
    INSTALL,
    ROUTE,
    documented_lines,
    install_documented,
    is_syntax,
    run_line,
    user_env,
    workdir,
)

COMMAND = f"{ROUTE} hc_smooth scans/*.ply -o smoothed/"
HELP = f"{ROUTE} hc_smooth --help"
# Every concrete documented line, and the test that runs it.
TESTED = {
    INSTALL: "test_bpy_route (install_documented)",
    COMMAND: "test_bpy_route",
    HELP: "test_bpy_route",
    f"{ROUTE} run examples/smooth_with_operators.py": "test_examples",
    f"{ROUTE} run scene.blend examples/smooth_with_operators.py -- Scan smoothed.blend": "test_examples",
    f"{ROUTE} run examples/smooth_arrays_with_core.py": "test_examples",
    f"{ROUTE} run scene.blend examples/smooth_arrays_with_core.py -- Scan": "test_examples",
    f"{ROUTE} run examples/batch_from_script.py -- scans/*.ply -o smoothed/": "test_examples",
    f"find scans -name '*.ply' -print0 | xargs -0 -P 4 -n 1 {ROUTE} hc_smooth -o smoothed/": "test_parallel",
    f"parallel -j 4 {ROUTE} hc_smooth -o smoothed/ {{}} ::: scans/*.ply": "not run: GNU parallel",
}


def make_scans(folder, names=("a", "b")):
    folder.mkdir()
    for seed, name in enumerate(names):
        bpy.ops.wm.read_homefile(use_empty=True)
        select_only(noisy_sphere(name=name, subdivisions=3, seed=seed))
        bpy.ops.wm.ply_export(
            filepath=str(folder / f"{name}.ply"), export_selected_objects=True, export_uv=False, export_normals=False
        )


@pytest.fixture(scope="module")
def user_folder(extension_zip, tmp_path_factory):
    return install_documented(extension_zip, tmp_path_factory.mktemp("route"))


def test_every_documented_line_of_the_route_is_run_by_a_test():
    documented = {line for path in DOCUMENTS for line in documented_lines(path) if not is_syntax(line)}
    assert documented == set(TESTED)


@pytest.mark.parametrize(
    "path", [p for p in DOCUMENTS if p.suffix in (".md", ".py") and p.parent.name != "scripts"], ids=lambda p: p.name
)
def test_every_blender_line_has_the_route_beside_it(path):
    """In each shell block of the docs with `blender` lines (each example's docstring), as many route lines."""
    text = path.read_text()
    blocks = re.findall(r"```sh\n(.*?)```", text, re.S) if path.suffix == ".md" else [text.split('"""')[1]]
    blender = re.compile(r"(^|\s)blender (-b|--command)")
    for block in blocks:
        lines = block.splitlines()
        blender_lines = sum(bool(blender.search(line)) for line in lines)
        route_lines = sum(line.strip().startswith(ROUTE) or f" {ROUTE} " in line for line in lines)
        assert route_lines == blender_lines or not blender_lines, block


def test_documented_command_smooths_the_scans(scene, user_folder, tmp_path):
    work = workdir(tmp_path)
    make_scans(work / "scans")
    completed = run_line(COMMAND, work, user_env(user_folder))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "2 of 2 files smoothed" in completed.stdout
    assert sorted(os.listdir(work / "smoothed")) == ["a.ply", "b.ply"]
    assert (work / "smoothed" / "a.ply").read_bytes() != (work / "scans" / "a.ply").read_bytes()
    # The command's own guarantees hold through the route: an existing result is not replaced (exit 2).
    again = run_line(COMMAND, work, user_env(user_folder))
    assert again.returncode == 2, again.stdout + again.stderr


def test_documented_help_is_the_commands(user_folder, tmp_path):
    completed = run_line(HELP, workdir(tmp_path), user_env(user_folder))
    assert completed.returncode == 0, completed.stderr
    assert "--output-dir" in completed.stdout and "--points" in completed.stdout


def test_a_failing_file_is_exit_status_1(scene, user_folder, tmp_path):
    work = workdir(tmp_path)
    make_scans(work / "scans", names=("a",))
    (work / "scans" / "broken.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nend_header\n1 2\n")
    completed = run_line(COMMAND, work, user_env(user_folder))
    assert completed.returncode == 1, completed.stdout + completed.stderr
    assert "broken.ply: FAILED" in completed.stdout and os.listdir(work / "smoothed") == ["a.ply"]


def test_not_installed_says_how_to_install(tmp_path):
    completed = run_line(COMMAND, workdir(tmp_path / "work"), user_env(tmp_path / "empty"))
    assert completed.returncode == 1
    assert "HC Smooth is not installed in the Blender user folder" in completed.stderr
    assert f"{tmp_path / 'empty'}" in completed.stderr and "install" in completed.stderr
    assert "Traceback" not in completed.stderr


def test_default_user_folder_is_its_own_not_blenders(scene, extension_zip, tmp_path):
    """No --user-folder, no BLENDER_USER_RESOURCES: ~/.local/share/hc_smooth/bpy-X.Y, never ~/.config/blender."""
    home = tmp_path / "home"
    home.mkdir()
    env = {key: value for key, value in os.environ.items() if key not in ("BLENDER_USER_RESOURCES", "XDG_DATA_HOME")}
    env["HOME"] = str(home)
    work = workdir(tmp_path / "work")
    (work / "build").mkdir()
    (work / "build" / extension_zip.name).symlink_to(extension_zip)
    installed = run_line(INSTALL, work, env)
    assert installed.returncode == 0, installed.stdout + installed.stderr
    version = ".".join(importlib.metadata.version("bpy").split(".")[:2])
    folder = home / ".local" / "share" / "hc_smooth" / f"bpy-{version}"
    assert (folder / "extensions" / "user_default" / "hc_smooth" / "blender_manifest.toml").is_file()
    make_scans(work / "scans", names=("a",))
    completed = run_line(COMMAND, work, env)  # a later process finds and enables it there
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert os.listdir(home) == [".local"]  # no ~/.config/blender (Blender's own user folder)


@pytest.mark.parametrize("where", ["first", "last"])
def test_user_folder_option_before_or_after_the_subcommand(extension_zip, tmp_path, where):
    work = workdir(tmp_path / "work")
    line = f"{ROUTE} --user-folder mine install {extension_zip}"
    if where == "last":
        line = f"{ROUTE} install {extension_zip} --user-folder mine"
    completed = run_line(line, work, user_env(tmp_path / "other"))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert (work / "mine" / "extensions" / "user_default" / "hc_smooth").is_dir()
    assert not (tmp_path / "other").exists()


@pytest.mark.parametrize(
    "args, message",
    [
        ("install --user-folder mine/deep", "install takes one extension zip: install [--user-folder DIR] ZIP"),
        ("install a.zip b.zip --user-folder mine/deep", "(given: a.zip b.zip)"),
        ("install missing.zip --user-folder mine/deep", "missing.zip does not exist"),
        ("--user-folder mine/deep install missing.zip --user-folder other", "give --user-folder once"),
        ("hc_smooth scans -o out --user-folder", "--user-folder needs a folder"),
    ],
)
def test_a_refused_install_makes_no_user_folder(tmp_path, args, message):
    work = workdir(tmp_path / "work")
    completed = run_line(f"{ROUTE} {args}", work, user_env(tmp_path / "env", XDG_DATA_HOME=str(tmp_path / "xdg")))
    assert completed.returncode == 2 and message in completed.stderr, completed.stderr
    assert "Traceback" not in completed.stderr
    assert sorted(os.listdir(work)) == ["examples", "scripts"] and sorted(os.listdir(tmp_path)) == ["work"]


@pytest.mark.parametrize("args", ["install build/hc_smooth-0.1.0.zip", "hc_smooth scans -o out"])
def test_a_python_without_bpy_is_told_what_to_do_and_nothing_is_made(tmp_path, args):
    """`python -S` has no site-packages, so no bpy: a plain message, exit status 1, no user folder (not
    even the default one, which is named after the bpy version)."""
    work = workdir(tmp_path / "work")
    (work / "build").mkdir()
    (work / "build" / "hc_smooth-0.1.0.zip").write_bytes(b"PK")
    env = {key: value for key, value in os.environ.items() if key != "BLENDER_USER_RESOURCES"}
    env.update(XDG_DATA_HOME=str(tmp_path / "xdg"), HOME=str(tmp_path / "home"))
    completed = subprocess.run(
        [sys.executable, "-S", "scripts/hc_smooth_bpy.py", *args.split()],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert completed.returncode == 1, completed.stdout + completed.stderr
    assert f"this Python ({sys.executable}) has no bpy module" in completed.stderr
    assert "python scripts/hc_smooth_files.py" in completed.stderr and "Traceback" not in completed.stderr
    assert sorted(os.listdir(tmp_path)) == ["work"] and sorted(os.listdir(work)) == ["build", "examples", "scripts"]


@pytest.mark.parametrize(
    "args, message",
    [
        ("", "give a subcommand"),
        ("smooth a.ply", "give a subcommand"),
        ("install", "install takes one extension zip"),
        ("install missing.zip", "missing.zip does not exist"),
        ("run", "usage: run"),
        ("run examples/batch_from_script.py a.ply", "usage: run"),
        ("run nothing.py", "no script nothing.py"),
        ("run missing.blend examples/smooth_with_operators.py", "no file missing.blend"),
    ],
)
def test_usage_errors_say_what_is_wrong_and_exit_2(user_folder, tmp_path, args, message):
    completed = run_line(f"{ROUTE} {args}".strip(), workdir(tmp_path), user_env(user_folder))
    assert completed.returncode == 2 and message in completed.stderr, completed.stderr
    assert "Traceback" not in completed.stderr
