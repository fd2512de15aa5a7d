"""The example scripts of docs/python_api.md, run as `blender -b --python` would run them (runpy, in the
headless bpy process with the extension installed), asserting on what they print and do."""

import pathlib
import runpy
import sys

import bpy
import numpy as np
import pytest

from blender_scene import noisy_sphere, positions_of

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"


def run_example(name, monkeypatch, *args):
    argv = ["blender", "-b", "--python", str(EXAMPLES / name)] + (["--", *args] if args else [])
    monkeypatch.setattr(sys, "argv", argv)
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")


def test_operators_example_on_try_out_sphere(scene, monkeypatch, capsys):
    run_example("smooth_with_operators.py", monkeypatch)
    out = capsys.readouterr().out
    assert "shape keys: ['Basis', 'HC Smooth']" in out
    assert "smoothed 'Scan' (642 vertices)" in out
    assert bpy.context.mode == "OBJECT"


def test_operators_example_on_named_object_saves_copy(scene, monkeypatch, tmp_path):
    obj = noisy_sphere(name="Mine")
    before = positions_of(obj.data).copy()
    run_example("smooth_with_operators.py", monkeypatch, "Mine", str(tmp_path / "copy.blend"))
    after = positions_of(obj.data)
    assert np.abs(after - before).max() > 1e-4
    assert (tmp_path / "copy.blend").is_file()


def test_core_example_keeps_volume_better_than_laplacian(scene, monkeypatch, capsys):
    run_example("smooth_arrays_with_core.py", monkeypatch)
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if "volume" in line}
    hc = float(lines["HC"].rsplit("volume", 1)[1].strip().rstrip("%"))
    laplacian = float(lines["Laplacian"].rsplit("volume", 1)[1].strip().rstrip("%"))
    assert abs(hc) * 5 < abs(laplacian)


def test_batch_example_runs_the_command(scene, monkeypatch, capsys, tmp_path):
    obj = noisy_sphere()
    bpy.ops.wm.stl_export(filepath=str(tmp_path / "scan.stl"))
    run_example("batch_from_script.py", monkeypatch, str(tmp_path / "scan.stl"), "-o", str(tmp_path / "out"))
    assert "1 of 1 files smoothed" in capsys.readouterr().out
    assert (tmp_path / "out" / "scan.stl").is_file()
    with pytest.raises(SystemExit) as exit_info:  # a failure becomes Blender's exit status
        run_example("batch_from_script.py", monkeypatch, str(tmp_path / "missing.stl"), "-o", str(tmp_path / "out"))
    assert exit_info.value.code == 1
