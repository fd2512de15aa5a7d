"""The example scripts of docs/python_api.md, run both ways a user runs them:

- with Blender as a Python module, as subprocesses of `python scripts/hc_smooth_bpy.py run ...`, exactly
  as the docs write the lines (HC Smooth installed in an earlier process, enabled by the route);
- as `blender -b --python` runs them: in this process (runpy), where HC Smooth is already enabled, as a
  Blender enables it from its preferences (there is no blender binary here).
"""

import pathlib
import re
import runpy
import subprocess
import sys

import bpy
import numpy as np
import pytest
from blender_scene import noisy_sphere, positions_of, select_only
from bpy_route import ROUTE, install_documented, run_line, user_env, workdir

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
OPERATORS_TRY = f"{ROUTE} run examples/smooth_with_operators.py"
OPERATORS_SCENE = f"{ROUTE} run scene.blend examples/smooth_with_operators.py -- Scan smoothed.blend"
CORE_TRY = f"{ROUTE} run examples/smooth_arrays_with_core.py"
CORE_SCENE = f"{ROUTE} run scene.blend examples/smooth_arrays_with_core.py -- Scan"
BATCH = f"{ROUTE} run examples/batch_from_script.py -- scans/*.ply -o smoothed/"


@pytest.fixture(scope="module")
def user_folder(extension_zip, tmp_path_factory):
    return install_documented(extension_zip, tmp_path_factory.mktemp("examples"))


@pytest.fixture
def work(scene, tmp_path):
    """A working folder with scripts/, examples/, scene.blend (a noisy 'Scan') and scans/scan.stl."""
    folder = workdir(tmp_path / "work")
    obj = noisy_sphere(name="Scan", subdivisions=5)  # 2562 vertices, unlike the try-out sphere's 642
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "scene.blend"), copy=True)
    (folder / "scans").mkdir()
    select_only(obj)
    bpy.ops.wm.ply_export(
        filepath=str(folder / "scans" / "scan.ply"), export_selected_objects=True, export_uv=False, export_normals=False
    )
    bpy.ops.wm.read_homefile(use_empty=True)
    return folder


def volume_changes(out):
    """{'HC': percent, 'Laplacian': percent} from the core example's lines."""
    return {match[1]: float(match[2]) for match in re.finditer(r"^(HC|Laplacian)\s.*volume ([-+\d.]+)%", out, re.M)}


def mesh_positions(blend, name):
    with bpy.data.libraries.load(str(blend)) as (source, target):
        target.meshes = [name]
    mesh = target.meshes[0]
    positions = positions_of(mesh).copy()
    bpy.data.meshes.remove(mesh)
    return positions


# --- Blender as a Python module: the documented lines, as subprocesses -----------------------------------


def test_operators_example_try_out(work, user_folder):
    completed = run_line(OPERATORS_TRY, work, user_env(user_folder))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "shape keys: ['Basis', 'HC Smooth']" in completed.stdout
    assert "smoothed 'Scan' (642 vertices)" in completed.stdout


def test_operators_example_on_a_scene_saves_a_smoothed_copy(work, user_folder):
    completed = run_line(OPERATORS_SCENE, work, user_env(user_folder))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "smoothed 'Scan' (2562 vertices)" in completed.stdout
    before, after = mesh_positions(work / "scene.blend", "Scan"), mesh_positions(work / "smoothed.blend", "Scan")
    assert before.shape == after.shape and np.abs(after - before).max() > 1e-4


def test_core_example_try_out_keeps_volume_better_than_laplacian(work, user_folder):
    completed = run_line(CORE_TRY, work, user_env(user_folder))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    change = volume_changes(completed.stdout)
    assert abs(change["HC"]) * 5 < abs(change["Laplacian"])


def test_core_example_on_a_scene(work, user_folder):
    completed = run_line(CORE_SCENE, work, user_env(user_folder))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    change = volume_changes(completed.stdout)
    assert abs(change["HC"]) * 5 < abs(change["Laplacian"])


def test_batch_example_runs_the_command(work, user_folder):
    completed = run_line(BATCH, work, user_env(user_folder))
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "1 of 1 files smoothed" in completed.stdout
    assert (work / "smoothed" / "scan.ply").is_file()
    (work / "scans" / "broken.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nend_header\n1 2\n")
    failed = run_line(BATCH.replace("smoothed/", "again/"), work, user_env(user_folder))
    assert failed.returncode == 1, failed.stdout + failed.stderr  # a failed file is the exit status


def run_directly(example, cwd, env, *args):
    """`python examples/NAME.py -- ARGS` in a Python with bpy: no route, nothing enabled beforehand."""
    return subprocess.run(
        [sys.executable, str(EXAMPLES / example), *(["--", *args] if args else [])],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_examples_enable_an_installed_hc_smooth_themselves(work, user_folder):
    """In a bpy process where HC Smooth is installed but not enabled (the module enables nothing at start)."""
    batch = run_directly("batch_from_script.py", work, user_env(user_folder), "scans/scan.ply", "-o", "direct")
    assert batch.returncode == 0, batch.stdout + batch.stderr
    assert (work / "direct" / "scan.ply").is_file()
    operators = run_directly("smooth_with_operators.py", work, user_env(user_folder))
    assert operators.returncode == 0 and "smoothed 'Scan' (642 vertices)" in operators.stdout, operators.stderr


@pytest.mark.parametrize("example", ["batch_from_script.py", "smooth_arrays_with_core.py", "smooth_with_operators.py"])
def test_examples_say_when_hc_smooth_is_not_installed(example, tmp_path):
    completed = run_directly(example, tmp_path, user_env(tmp_path / "empty"), "scan.ply", "-o", "out")
    assert completed.returncode == 1
    assert "HC Smooth is not installed in this Blender's user folder" in completed.stderr, completed.stderr
    assert "Traceback" not in completed.stderr


def test_examples_share_one_way_to_find_hc_smooth():
    """Each example is standalone, so each carries hc_smooth_package(): the copies must not drift."""
    bodies = {
        re.search(r"\ndef hc_smooth_package\(\):\n(?:    .*\n|\n)+", (EXAMPLES / name).read_text())[0]
        for name in ("batch_from_script.py", "smooth_arrays_with_core.py", "smooth_with_operators.py")
    }
    assert len(bodies) == 1


# --- As `blender -b --python` runs them: HC Smooth already enabled (in this process) ---------------------


def run_example(name, monkeypatch, *args):
    argv = ["blender", "-b", "--python", str(EXAMPLES / name)] + (["--", *args] if args else [])
    monkeypatch.setattr(sys, "argv", argv)
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")


def test_operators_example_on_named_object_saves_copy(scene, monkeypatch, tmp_path):
    obj = noisy_sphere(name="Mine")
    before = positions_of(obj.data).copy()
    run_example("smooth_with_operators.py", monkeypatch, "Mine", str(tmp_path / "copy.blend"))
    after = positions_of(obj.data)
    assert np.abs(after - before).max() > 1e-4
    assert (tmp_path / "copy.blend").is_file()
    assert bpy.context.mode == "OBJECT"


def test_core_example_keeps_volume_better_than_laplacian(scene, monkeypatch, capsys):
    run_example("smooth_arrays_with_core.py", monkeypatch)
    change = volume_changes(capsys.readouterr().out)
    assert abs(change["HC"]) * 5 < abs(change["Laplacian"])


def test_batch_example_runs_the_command_in_process(scene, monkeypatch, capsys, tmp_path):
    noisy_sphere()
    bpy.ops.wm.stl_export(filepath=str(tmp_path / "scan.stl"))
    run_example("batch_from_script.py", monkeypatch, str(tmp_path / "scan.stl"), "-o", str(tmp_path / "out"))
    assert "1 of 1 files smoothed" in capsys.readouterr().out
    assert (tmp_path / "out" / "scan.stl").is_file()
    with pytest.raises(SystemExit) as exit_info:  # a failure becomes Blender's exit status
        run_example("batch_from_script.py", monkeypatch, str(tmp_path / "missing.stl"), "-o", str(tmp_path / "out"))
    assert exit_info.value.code == 1
