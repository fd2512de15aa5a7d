"""The file route without Blender: scripts/hc_smooth_files.py smooths PLY, OBJ and STL files in a Python
where bpy cannot be imported, with the command's options, messages and exit status; .blend files and a
Python without NumPy get a plain message. (Its bytes against `blender -b -c hc_smooth`:
tests/blender/test_file_route_bytes.py.)"""

import os
import re
import shlex
import subprocess
import sys

import numpy as np
import pytest
import scan_files
from file_route import OPTION_SETS, ROOT, SCRIPT, WITHOUT_BLENDER, inputs_for, run_without_blender, scan_folder

IMPORT_ALL = """
import importlib, pkgutil, sys
sys.path.insert(0, sys.argv[1])
import cli.standalone as standalone  # stdlib only; loads the package without its __init__
package = standalone.load(sys.argv[1])
names = []
for sub in ("jobs", "cli", "core"):
    module = importlib.import_module("hc_smooth." + sub)
    for info in pkgutil.walk_packages(module.__path__, module.__name__ + "."):
        if info.name != "hc_smooth.cli.blend":
            importlib.import_module(info.name)
            names.append(info.name)
try:
    importlib.import_module("hc_smooth.cli.blend")
except ModuleNotFoundError as error:
    print("blend:", error.name)
print(len(names), "hc_smooth.jobs.points" in names, "hc_smooth.cli.file_route" in names)
"""


def test_the_route_imports_without_blender():
    """jobs/, cli/ (but its .blend part) and core/ import with bpy unimportable; cli/blend.py is what needs it."""
    code = WITHOUT_BLENDER.replace('runpy.run_path(script, run_name="__main__")', "exec(open(script).read())")
    probe = ROOT / "build" / "probe_import_all.py"
    probe.parent.mkdir(exist_ok=True)
    probe.write_text(IMPORT_ALL)
    try:
        completed = subprocess.run(
            [sys.executable, "-c", code, str(probe), str(ROOT)], capture_output=True, text=True, timeout=120
        )
    finally:
        probe.unlink()
    assert completed.returncode == 0, completed.stderr
    lines = completed.stdout.splitlines()
    assert lines[0] == "blend: bpy"
    count, points, route = lines[1].split()
    assert int(count) >= 20 and points == "True" and route == "True"
    assert completed.stderr.strip().endswith("loaded:")  # no Blender module was loaded


def test_a_folder_of_scans_smooths_without_blender(tmp_path):
    folder = scan_folder(tmp_path / "scans")
    before = {path.name: path.read_bytes() for path in folder.iterdir()}
    completed = run_without_blender([folder, "-o", tmp_path / "smoothed"], cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "4 of 4 files smoothed" in completed.stdout
    assert completed.stderr.strip() == "loaded:"  # nothing tried to import Blender, nothing else said
    assert sorted(os.listdir(tmp_path / "smoothed")) == sorted(before)
    for name, data in before.items():
        assert (folder / name).read_bytes() == data  # the inputs as they were
        out = (tmp_path / "smoothed" / name).read_bytes()
        assert out != data and out[:5] == data[:5]  # smoothed, in its input's format


@pytest.mark.parametrize("kind, options", OPTION_SETS[1:])
def test_options_run_without_blender(tmp_path, kind, options):
    inputs = inputs_for(kind, tmp_path / "in", options)
    completed = run_without_blender([*inputs, "-o", tmp_path / "out", *options], cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert completed.stderr.strip() == "loaded:"
    assert os.listdir(tmp_path / "out")


def test_the_smoothing_is_the_cores(tmp_path):
    """A double PLY's result is core.MeshSmoother's run with the options the jobs give core (as in Blender)."""
    import cli.standalone as standalone
    import core

    standalone.load(ROOT)
    arguments, mesh_jobs = standalone.command(ROOT).arguments, sys.modules["hc_smooth.jobs.mesh"]

    positions, faces = scan_files.octahedron(noise=0.02, seed=5)
    vertex = [("x", "double"), ("y", "double"), ("z", "double")]
    face = [("vertex_indices", ("list", "uchar", "int"))]
    elements = [("vertex", vertex, positions.tolist()), ("face", face, [[f] for f in faces.tolist()])]
    (tmp_path / "a.ply").write_bytes(scan_files.ply(elements, "binary_little_endian"))
    completed = run_without_blender(["a.ply", "-o", "out", "--iterations", "7", "--slide"], cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    data = (tmp_path / "out" / "a.ply").read_bytes()
    body = data[data.index(b"end_header\n") + len(b"end_header\n") :]
    smoothed = np.frombuffer(body[: 24 * len(positions)], "<f8").reshape(-1, 3)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    plan = arguments.parse(["a.ply", "-o", str(tmp_path / "again"), "--iterations", "7", "--slide"])
    options = mesh_jobs.core_options(plan.settings, plan.given)
    assert options["iterations"] == 7 and options["keep_in_place"] is False
    expected = core.MeshSmoother(positions, edges, faces=faces, **options).run()
    assert expected.dtype == np.float64
    np.testing.assert_array_equal(smoothed, expected)


def test_a_blend_file_needs_blender(tmp_path):
    folder = scan_folder(tmp_path / "scans")
    (folder / "scene.blend").write_bytes(b"BLENDER-v405" + bytes(100))
    completed = run_without_blender([folder, "-o", tmp_path / "out"], cwd=tmp_path)
    assert completed.returncode == 1, completed.stdout + completed.stderr
    assert "scene.blend: FAILED: a .blend file needs Blender: smooth it with `blender -b -c hc_smooth`" in (
        completed.stdout
    )
    assert "4 of 5 files smoothed" in completed.stdout and "Traceback" not in completed.stderr
    assert sorted(os.listdir(tmp_path / "out")) == ["binary.ply", "grouped.obj", "part.stl", "rich.ply"]


def test_usage_errors_are_the_commands(tmp_path):
    completed = run_without_blender(["a.ply"], cwd=tmp_path)
    assert completed.returncode == 2
    assert "give either -o OUTDIR or --in-place" in completed.stderr and "Traceback" not in completed.stderr
    helped = run_without_blender(["--help"], cwd=tmp_path)
    assert helped.returncode == 0 and helped.stdout.startswith(f"usage: python {SCRIPT}")


def test_a_python_without_numpy_is_told_what_to_install(tmp_path):
    """`python -S` has no site-packages: no NumPy, no SciPy."""
    scan_folder(tmp_path / "scans")
    completed = subprocess.run(
        [sys.executable, "-S", str(SCRIPT), "scans", "-o", "out"], cwd=tmp_path, capture_output=True, text=True
    )
    assert completed.returncode == 2
    assert "has no numpy, which HC Smooth needs: python -m pip install numpy scipy" in completed.stderr
    assert "Traceback" not in completed.stderr and not (tmp_path / "out").exists()


ROUTE = "python scripts/hc_smooth_files.py"
DOCUMENTS = (ROOT / "README.md", ROOT / "docs" / "command_line.md", SCRIPT)


def documented_lines():
    lines = {line.strip() for path in DOCUMENTS for line in path.read_text().splitlines()}
    # A cluster's line needs the reader's scheduler: test_batch.py runs --scheduler on a LocalCluster.
    return sorted(
        line for line in lines if line.startswith(ROUTE) and not re.search(r"\.\.\.|\[|INPUT|--scheduler", line)
    )


def test_the_documented_lines_run_as_written_without_blender(tmp_path):
    """Each line of the README, docs/command_line.md and the script's docstring, through the shell (globs
    expand), in a folder with the repository's scripts/ and a scans/ folder, `python` a Python without bpy."""
    lines = documented_lines()
    assert f"{ROUTE} scans/ -o smoothed/" in lines and len(lines) >= 3
    python = f"{shlex.quote(sys.executable)} -c {shlex.quote(WITHOUT_BLENDER)}"
    for number, line in enumerate(lines):
        work = tmp_path / str(number)
        work.mkdir()
        (work / "scripts").symlink_to(ROOT / "scripts")
        scan_folder(work / "scans")
        completed = subprocess.run(
            line.replace("python ", python + " ", 1), shell=True, cwd=work, capture_output=True, text=True, timeout=600
        )
        assert completed.returncode == 0, line + completed.stdout + completed.stderr
        assert completed.stderr.strip() == "loaded:", line
        if "--help" not in line:
            assert os.listdir(work / "smoothed") and "files smoothed" in completed.stdout, line
