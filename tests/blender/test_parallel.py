"""One process per file: the `xargs -P` line of docs/command_line.md for Blender as a Python module
(`scripts/hc_smooth_bpy.py hc_smooth`; there is no blender binary here), as written, on a folder of
generated scans."""

import os
import sys
import time

import bpy
import pytest
from blender_scene import ADDON, noisy_sphere, select_only
from bpy_route import ROOT, ROUTE, install_documented, run_line, user_env, workdir

DOCS = ROOT / "docs" / "command_line.md"
SCANS = 6


def documented_xargs_line():
    (line,) = [line for line in DOCS.read_text().splitlines() if f"| xargs -0 -P 4 -n 1 {ROUTE} hc_smooth" in line]
    return line


@pytest.fixture(scope="module")
def user_folder(extension_zip, tmp_path_factory):
    """A Blender user folder with HC Smooth installed from the built zip, shared by the processes."""
    return install_documented(extension_zip, tmp_path_factory.mktemp("parallel"))


def make_scans(folder, count=SCANS):
    folder.mkdir()
    for seed in range(count):
        bpy.ops.wm.read_homefile(use_empty=True)
        select_only(noisy_sphere(name=f"scan{seed}", subdivisions=4, seed=seed))
        bpy.ops.wm.ply_export(
            filepath=str(folder / f"scan{seed}.ply"),
            export_selected_objects=True,
            export_uv=False,
            export_normals=False,
        )


def run_documented_line(cwd, user_folder):
    start = time.perf_counter()
    completed = run_line(documented_xargs_line(), workdir(cwd), user_env(user_folder))
    print(f"xargs -P 4 over {len(os.listdir(cwd / 'scans'))} scans: {time.perf_counter() - start:.1f} s")
    return completed


def test_xargs_line_smooths_a_folder_like_one_process(addon, user_folder, tmp_path):
    make_scans(tmp_path / "scans")
    completed = run_documented_line(tmp_path, user_folder)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert sorted(os.listdir(tmp_path / "smoothed")) == [f"scan{seed}.ply" for seed in range(SCANS)]
    assert completed.stdout.count("1 of 1 files smoothed") == SCANS
    # A parallel result equals the same file smoothed by the command in this process, to the bit.
    cli = sys.modules[ADDON + ".cli"]
    assert cli.main([str(tmp_path / "scans" / "scan3.ply"), "-o", str(tmp_path / "single")]) == 0
    assert (tmp_path / "single" / "scan3.ply").read_bytes() == (tmp_path / "smoothed" / "scan3.ply").read_bytes()
    assert (tmp_path / "smoothed" / "scan3.ply").read_bytes() != (tmp_path / "scans" / "scan3.ply").read_bytes()


def test_xargs_fails_when_a_file_fails_and_the_others_are_written(addon, user_folder, tmp_path):
    make_scans(tmp_path / "scans", count=3)
    (tmp_path / "scans" / "broken.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nend_header\n1 2\n")
    completed = run_documented_line(tmp_path, user_folder)
    assert completed.returncode == 123, completed.stdout + completed.stderr  # xargs: some invocation failed
    assert "broken.ply: FAILED" in completed.stdout
    assert sorted(os.listdir(tmp_path / "smoothed")) == ["scan0.ply", "scan1.ply", "scan2.ply"]
