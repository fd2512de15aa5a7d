"""The `blender -c hc_smooth` command, driven through its entry function (the bpy module cannot run
`blender -c`): formats, failures that leave nothing behind, inputs never overwritten, .blend copies."""

import hashlib
import os
import sys

import bpy
import numpy as np
import pytest

import core
from blender_scene import make_mesh_object, noisy_sphere, positions_of, select_only
from blender_scene import ADDON

FORMATS = ("ply", "obj", "stl")


@pytest.fixture
def cli(addon):
    return sys.modules[ADDON + ".cli"]


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def export_noisy_sphere(path, seed=0):
    """A closed noisy icosphere written with Blender's exporter (PLY without UV/normal splits)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere(seed=seed)
    select_only(obj)
    ext = os.path.splitext(str(path))[1][1:]
    options = {"export_uv": False, "export_normals": False} if ext == "ply" else {}
    getattr(bpy.ops.wm, ext + "_export")(filepath=str(path), export_selected_objects=True, **options)
    return path


def import_positions(path):
    """Positions and edges of the single mesh in ``path``, read back with Blender's importer."""
    bpy.ops.wm.read_homefile(use_empty=True)
    ext = os.path.splitext(str(path))[1][1:]
    getattr(bpy.ops.wm, ext + "_import")(filepath=str(path))
    (obj,) = [obj for obj in bpy.data.objects if obj.type == "MESH"]
    edges = np.empty(len(obj.data.edges) * 2, dtype=np.int64)
    obj.data.edges.foreach_get("vertices", edges)
    return positions_of(obj.data), edges.reshape(-1, 2)


def leftovers(folder):
    return [name for name in os.listdir(folder) if ".hc_smooth-" in name]


def test_registered_with_blenders_command_registry(cli, monkeypatch):
    assert cli._handle is not None  # registered by the add-on's register()
    calls = []
    cli.unregister()
    monkeypatch.setattr(bpy.utils, "register_cli_command", lambda *args: calls.append(args) or "handle")
    monkeypatch.setattr(bpy.utils, "unregister_cli_command", lambda handle: calls.append(("unregister", handle)))
    cli.register()
    cli.unregister()
    monkeypatch.undo()
    cli.register()
    assert calls == [("hc_smooth", cli.main), ("unregister", "handle")]
    assert cli._handle is not None


def test_help(cli, capsys):
    assert cli.main(["--help"]) == 0
    text = capsys.readouterr().out
    for option in ("--output-dir", "--in-place", "--format", "--method", "--alpha", "--beta", "--iterations",
                   "--mode", "--fixed-group", "--invert-group", "--pin-boundary", "--points", "--object"):
        assert option in text


@pytest.mark.parametrize("argv, message", [
    (["a.ply"], "either -o OUTDIR or --in-place"),
    (["a.ply", "-o", "out", "--in-place"], "either -o OUTDIR or --in-place"),
    (["a.ply", "-o", "out", "--alpha", "1.5"], "outside [0, 1]"),
    (["a.ply", "-o", "out", "--iterations", "-1"], "negative"),
    (["a.ply", "-o", "out", "--invert-group"], "--invert-group needs --fixed-group"),
    (["a.ply", "-o", "out", "--method", "taubin"], "invalid choice"),
    (["x/a.ply", "y/a.ply", "-o", "out"], "would both be written"),
])
def test_usage_errors(cli, capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv) == 2
    assert message in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_refuses_to_overwrite_input(cli, capsys, tmp_path):
    source = export_noisy_sphere(tmp_path / "scan.ply")
    before = digest(source)
    assert cli.main([str(source), "-o", str(tmp_path)]) == 2
    assert "overwrite an input" in capsys.readouterr().err
    assert digest(source) == before


@pytest.mark.parametrize("fmt", FORMATS)
def test_smooths_each_format_like_the_operator(cli, capsys, tmp_path, fmt):
    source = export_noisy_sphere(tmp_path / f"scan.{fmt}")
    before = digest(source)
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--iterations", "7", "--beta", "0.7"]) == 0
    out = capsys.readouterr().out
    assert "[1/1]" in out and "1 of 1 files smoothed" in out and "volume" in out
    assert digest(source) == before
    result, _ = import_positions(tmp_path / "out" / f"scan.{fmt}")
    # The same input through object.hc_smooth (the jobs code the command shares).
    positions, edges = import_positions(source)
    obj = bpy.data.objects[0]
    select_only(obj)
    assert bpy.ops.object.hc_smooth(iterations=7, beta=0.7) == {"FINISHED"}
    expected = positions_of(obj.data)
    assert not np.allclose(expected, positions)  # it did smooth
    tolerance = 2e-6 if fmt == "obj" else 0  # OBJ stores 6 decimals; PLY/STL float32 round-trip exactly
    np.testing.assert_allclose(result, expected, rtol=0, atol=tolerance)
    np.testing.assert_allclose(result, core.hc_smooth(positions, edges, alpha=0.1, beta=0.7, iterations=7),
                               rtol=0, atol=tolerance + 1e-5)
    assert leftovers(tmp_path / "out") == []


def test_format_option_and_folder_input(cli, tmp_path):
    scans = tmp_path / "scans"
    scans.mkdir()
    export_noisy_sphere(scans / "a.ply", seed=1)
    export_noisy_sphere(scans / "b.stl", seed=2)
    assert cli.main([str(scans), "-o", str(tmp_path / "out"), "--format", "obj"]) == 0
    assert sorted(name for name in os.listdir(tmp_path / "out") if name.endswith(".obj")) == ["a.obj", "b.obj"]
    with open(tmp_path / "out" / "a.obj") as obj_file:  # the material library is named after the result
        assert "mtllib .a" not in obj_file.read(2000)


def test_failures_are_reported_and_leave_no_output(cli, capsys, tmp_path):
    good = export_noisy_sphere(tmp_path / "good.ply")
    broken = tmp_path / "broken.ply"
    broken.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\n")
    text = tmp_path / "notes.txt"
    text.write_text("not a scan")
    out = tmp_path / "out"
    argv = [str(good), str(broken), str(tmp_path / "missing.stl"), str(text), "-o", str(out)]
    assert cli.main(argv) == 1
    captured = capsys.readouterr()
    assert "1 of 4 files smoothed" in captured.out
    assert "3 of 4 files failed" in captured.err
    assert f"{tmp_path / 'missing.stl'}: FAILED: no such file" in captured.out
    assert f"{text}: FAILED: unsupported file type '.txt'" in captured.out
    assert f"{broken}: FAILED:" in captured.out
    assert sorted(os.listdir(out)) == ["good.ply"]


def test_export_failure_keeps_the_previous_output(cli, capsys, tmp_path, monkeypatch):
    source = export_noisy_sphere(tmp_path / "scan.obj")
    out = tmp_path / "out"
    out.mkdir()
    (out / "scan.obj").write_text("previous result\n")

    def disk_full(*args):
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(cli.files, "_rename_material_library", disk_full)  # after the exporter wrote its files
    assert cli.main([str(source), "-o", str(out)]) == 1
    assert "FAILED: disk full (simulated)" in capsys.readouterr().out
    assert (out / "scan.obj").read_text() == "previous result\n"
    assert sorted(os.listdir(out)) == ["scan.obj"]  # no temporary .obj/.mtl left behind


def test_in_place_replaces_the_input(cli, tmp_path):
    source = export_noisy_sphere(tmp_path / "scan.stl")
    positions, _ = import_positions(source)
    assert cli.main([str(source), "--in-place"]) == 0
    result, _ = import_positions(source)
    assert not np.allclose(result, positions)
    assert sorted(os.listdir(tmp_path)) == ["scan.stl"]


def test_blend_named_object_with_fixed_group(cli, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    scan = noisy_sphere(name="Scan", seed=3)
    other = noisy_sphere(name="Other", seed=4)
    group = scan.vertex_groups.new(name="Keep")
    group.add(list(range(0, len(scan.data.vertices), 3)), 1.0, "REPLACE")
    scan_before, other_before = positions_of(scan.data).copy(), positions_of(other.data).copy()
    source = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    before = digest(source)
    out = tmp_path / "out"
    assert cli.main([str(source), "--object", "Scan", "--fixed-group", "Keep", "-o", str(out)]) == 0
    assert digest(source) == before
    bpy.ops.wm.open_mainfile(filepath=str(out / "scene.blend"))
    scan_after = positions_of(bpy.data.objects["Scan"].data)
    fixed = np.zeros(len(scan_after), dtype=bool)
    fixed[::3] = True
    assert np.array_equal(scan_after[fixed], scan_before[fixed])  # to the bit
    assert not np.allclose(scan_after[~fixed], scan_before[~fixed])
    assert np.array_equal(positions_of(bpy.data.objects["Other"].data), other_before)  # not named
    assert leftovers(out) == []


def test_blend_unknown_object_and_group(cli, capsys, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    noisy_sphere(name="Scan")
    source = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    out = tmp_path / "out"
    assert cli.main([str(source), "--object", "Nope", "-o", str(out)]) == 1
    assert "no object 'Nope'" in capsys.readouterr().out
    assert cli.main([str(source), "--fixed-group", "Nope", "-o", str(out)]) == 1
    assert "has no vertex group 'Nope'" in capsys.readouterr().out
    assert os.listdir(out) == []


def test_point_cloud_needs_points_flag(cli, capsys, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    points = np.random.default_rng(0).normal(size=(300, 3))
    obj = make_mesh_object("Points", points / np.linalg.norm(points, axis=1, keepdims=True))
    select_only(obj)
    source = tmp_path / "points.ply"
    bpy.ops.wm.ply_export(filepath=str(source), export_selected_objects=True)
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out)]) == 1
    assert "no edges: it is a point cloud (pass --points" in capsys.readouterr().out
    status = cli.main([str(source), "-o", str(out), "--points"])
    if hasattr(bpy.types, "OBJECT_OT_hc_smooth_points"):
        assert status == 0
        assert os.listdir(out) == ["points.ply"]
    else:  # the point-cloud operator is not part of this build yet: a clear failure, no output
        assert status == 1
        assert "object.hc_smooth_points, which is not registered" in capsys.readouterr().out
        assert os.listdir(out) == []
