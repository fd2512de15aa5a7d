"""`blender -b -c hc_smooth --jobs N`: the installed extension's command sends PLY, OBJ and STL files to Dask
workers (which run the file route without Blender) and smooths .blend files itself, with the serial run's
bytes; without Dask in Blender's Python it says what to do instead."""

import hashlib
import pathlib
import sys

import bpy
from blender_scene import ADDON, noisy_sphere

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "core"))
from file_route import scan_folder  # noqa: E402  (tests/core)


def digests(folder):
    return {path.name: hashlib.sha256(path.read_bytes()).hexdigest() for path in sorted(folder.iterdir())}


def test_jobs_in_blender_give_the_serial_bytes(addon, scene, tmp_path, capsys):
    cli = sys.modules[ADDON + ".cli"]
    scans = scan_folder(tmp_path / "scans")
    noisy_sphere(name="Scan")
    bpy.ops.wm.save_as_mainfile(filepath=str(scans / "scene.blend"))
    assert cli.main([str(scans), "-o", str(tmp_path / "serial")]) == 0
    capsys.readouterr()
    assert cli.main([str(scans), "-o", str(tmp_path / "jobs"), "--jobs", "2"]) == 0
    said = capsys.readouterr().out
    assert ".blend files run here, one at a time (the workers have no Blender)" in said
    assert "5 of 5 files smoothed" in said
    serial, jobs = digests(tmp_path / "serial"), digests(tmp_path / "jobs")
    assert jobs.keys() == serial.keys()
    assert {name: jobs[name] for name in jobs if name != "scene.blend"} == {
        name: serial[name] for name in serial if name != "scene.blend"
    }  # scene.blend ran here, as in the serial run


def test_blender_without_dask_says_what_to_do(addon, tmp_path, capsys, monkeypatch):
    cli = sys.modules[ADDON + ".cli"]
    scans = scan_folder(tmp_path / "scans")
    monkeypatch.setitem(sys.modules, "distributed", None)  # as a Python without it: the import fails
    assert cli.main([str(scans), "-o", str(tmp_path / "out"), "--jobs", "2"]) == 2
    err = capsys.readouterr().err
    assert "--jobs and --scheduler need Dask's distributed scheduler" in err
    assert "python scripts/hc_smooth_files.py --jobs N" in err and "xargs -P" in err
    assert not (tmp_path / "out").exists()
