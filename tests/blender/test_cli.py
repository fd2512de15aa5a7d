"""The `blender -c hc_smooth` command, driven through its entry function (the bpy module cannot run
`blender -c`): formats, failures that leave nothing behind, inputs never overwritten, .blend copies."""

import hashlib
import os
import subprocess
import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, make_mesh_object, noisy_sphere, positions_of, select_only

import core

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
    for option in (
        "--output-dir",
        "--in-place",
        "--format",
        "--overwrite",
        "--method",
        "--alpha",
        "--beta",
        "--iterations",
        "--mode",
        "--fixed-group",
        "--invert-group",
        "--pin-boundary",
        "--influence-group",
        "--invert-influence",
        "--verbose",
        "--points",
        "--object",
        "--rounds",
        "--steps-per-round",
        "--neighbours",
        "--reach",
        "--gap",
    ):
        assert option in text
    assert "Existing files are never replaced" in text and "keeps the input" in text
    assert "130 when interrupted" in text and "an OBJ's .mtl is neither read nor written" in text


def test_plain_settings_start_from_the_declared_defaults(addon):
    """The plain settings the command line hands to the job code (the parsing is tested in tests/core)."""
    arguments = sys.modules[ADDON + ".cli.arguments"]
    spec = sys.modules[ADDON + ".settings_spec"]
    point_settings = sys.modules[ADDON + ".operators.point_cloud"].PointSettings()
    for plain, declared in ((arguments.Settings(), spec.MESH), (point_settings, spec.POINTS)):
        assert vars(plain) == {s.name: s.default for s in declared}


@pytest.mark.parametrize(
    "argv, message",
    [
        (["a.ply"], "either -o OUTDIR or --in-place"),
        (["a.ply", "-o", "out", "--alpha", "1.5"], "blender -b -c hc_smooth: error: argument --alpha"),
        (["a.ply", "-o", "out", "--points", "--reach", "4"], "--reach (4) must not exceed --gap (3)"),
    ],
)
def test_usage_errors(cli, capsys, tmp_path, monkeypatch, argv, message):
    """Exit status 2, the reason on stderr, nothing written (every refusal: tests/core/test_cli_arguments.py)."""
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
    assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=7, beta=0.7) == {"FINISHED"}
    expected = positions_of(obj.data)
    assert not np.allclose(expected, positions)  # it did smooth
    tolerance = 2e-6 if fmt == "obj" else 0  # OBJ stores 6 decimals; PLY/STL float32 round-trip exactly
    np.testing.assert_allclose(result, expected, rtol=0, atol=tolerance)
    np.testing.assert_allclose(
        result, core.hc_smooth(positions, edges, alpha=0.1, beta=0.7, iterations=7), rtol=0, atol=tolerance + 1e-5
    )
    assert leftovers(tmp_path / "out") == []


def test_long_runs_print_progress_lines(cli, capsys, tmp_path, monkeypatch):
    """A file's smoothing prints 'smoothing FILE: N %' lines once it has run PROGRESS_FIRST seconds, at
    most every PROGRESS_EVERY (both 0 here: a line for every slice), with Keep Sharp Edges as with HC."""
    source = export_noisy_sphere(tmp_path / "scan.ply")
    monkeypatch.setattr(cli.one_file, "PROGRESS_FIRST", 0.0)
    monkeypatch.setattr(cli.one_file, "PROGRESS_EVERY", 0.0)
    for options in ([], ["--keep-sharp-edges"]):
        assert cli.main([str(source), "-o", str(tmp_path / f"out{len(options)}"), *options]) == 0
        lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("hc_smooth: smoothing")]
        percents = [int(line.rsplit(": ", 1)[1].rstrip(" %")) for line in lines]
        assert len(percents) >= 3 and percents == sorted(percents) and percents[-1] <= 100, lines
        assert all(str(source) in line for line in lines)


def test_automatic_amount_unless_alpha_or_iterations_given(cli, tmp_path):
    """Nothing given: the operator's default (Automatic Amount); --iterations or --alpha: exactly as given."""
    source = export_noisy_sphere(tmp_path / "scan.ply")
    positions, edges = import_positions(source)
    obj = bpy.data.objects[0]
    select_only(obj)
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    automatic = positions_of(obj.data)
    assert cli.main([str(source), "-o", str(tmp_path / "auto")]) == 0
    np.testing.assert_array_equal(import_positions(tmp_path / "auto" / "scan.ply")[0], automatic)
    for option, alpha, iterations in ((["--iterations", "3"], 0.1, 3), (["--alpha", "0.2"], 0.2, 10)):
        assert cli.main([str(source), "-o", str(tmp_path / option[0][2:]), *option]) == 0
        result, _ = import_positions(tmp_path / option[0][2:] / "scan.ply")
        expected = core.hc_smooth(
            positions, edges, alpha=float(np.float32(alpha)), beta=float(np.float32(0.6)), iterations=iterations
        )
        np.testing.assert_array_equal(result, expected)


def test_a_part_left_as_it_was_is_said(cli, capsys, tmp_path):
    """A noisy Cone (the Automatic Amount would shrink it to a point) comes back as it was, and the file's
    line and the summary say why."""
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.mesh.primitive_cone_add()
    obj = bpy.context.active_object
    noisy = positions_of(obj.data) + np.random.default_rng(0).normal(scale=0.35, size=(33, 3)).astype(np.float32)
    obj.data.vertices.foreach_set("co", noisy.ravel())
    select_only(obj)
    bpy.ops.wm.ply_export(filepath=str(tmp_path / "cone.ply"), export_selected_objects=True, export_normals=False)
    source, _ = import_positions(tmp_path / "cone.ply")
    capsys.readouterr()
    assert cli.main([str(tmp_path / "cone.ply"), "-o", str(tmp_path / "out")]) == 0
    said = capsys.readouterr().out
    assert said.count("1 part left as it was (smoothing would change its shape)") == 2  # the file's line, the summary
    np.testing.assert_array_equal(import_positions(tmp_path / "out" / "cone.ply")[0], source)


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

    monkeypatch.setattr(cli.files.os, "replace", disk_full)  # the temporary is written, then cannot be moved
    assert cli.main([str(source), "-o", str(out), "--overwrite"]) == 1
    monkeypatch.undo()
    assert "FAILED: disk full (simulated)" in capsys.readouterr().out
    assert (out / "scan.obj").read_text() == "previous result\n"
    assert sorted(os.listdir(out)) == ["scan.obj"]  # no temporary left behind


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
    assert not out.exists()


def export_points(path, points, group=None):
    """A loose-vertex mesh written to ``path`` (PLY, or .blend with vertex group "Keep" on the indices ``group``)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = make_mesh_object("Points", points)
    if group is not None:
        obj.vertex_groups.new(name="Keep").add([int(i) for i in group], 1.0, "REPLACE")
    select_only(obj)
    if str(path).endswith(".blend"):
        bpy.ops.wm.save_as_mainfile(filepath=str(path))
    else:
        bpy.ops.wm.ply_export(filepath=str(path), export_selected_objects=True)
    return path


def sphere_points(n=1000, sigma=0.01, seed=0):
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    return (points + rng.normal(scale=sigma, size=points.shape)).astype(np.float32)


def blend_positions(path, name="Points"):
    bpy.ops.wm.open_mainfile(filepath=str(path))
    return positions_of(bpy.data.objects[name].data)


def test_point_cloud_needs_points_flag(cli, capsys, tmp_path):
    source = export_points(tmp_path / "points.ply", sphere_points(300))
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out)]) == 1
    assert "no edges: it is a point cloud (pass --points" in capsys.readouterr().out
    assert cli.main([str(source), "-o", str(out), "--points"]) == 0
    assert os.listdir(out) == ["points.ply"]
    # The other way round: a mesh is not smoothed as a point cloud.
    mesh = export_noisy_sphere(tmp_path / "mesh.ply")
    assert cli.main([str(mesh), "-o", str(out), "--points"]) == 1
    assert "has edges: it is a mesh, not a point cloud (smooth it without --points)" in capsys.readouterr().out
    assert os.listdir(out) == ["points.ply"]


def test_points_take_the_point_options_and_report_the_real_amount(cli, capsys, tmp_path):
    source = export_points(tmp_path / "points.ply", sphere_points())
    before, _ = import_positions(source)
    out = tmp_path / "out"
    argv = [
        str(source),
        "-o",
        str(out),
        "--points",
        "--alpha",
        "0.05",
        "--beta",
        "0.6",
        "--rounds",
        "2",
        "--steps-per-round",
        "5",
        "--neighbours",
        "12",
        "--reach",
        "2",
        "--gap",
        "4",
    ]
    assert cli.main(argv) == 0
    text = capsys.readouterr().out
    assert "1000 points, 2 rounds of 5 steps (10 steps)" in text
    assert "0 iterations" not in text
    (row,) = [line for line in text.splitlines() if line.startswith(str(source)) and "->" not in line]
    assert "2 rounds of 5 steps" in row  # the summary table
    after, _ = import_positions(out / "points.ply")
    expected = core.smooth_point_cloud(
        before,
        alpha=0.05,
        beta=0.6,
        rounds=2,
        iterations_per_round=5,
        neighbours=12,
        spacing_factor=2.0,
        gap_factor=4.0,
    )
    assert not np.allclose(expected, before)
    assert np.array_equal(after, expected)
    # Without an amount the run follows the noise, as the operator's Automatic Amount; the line says what ran.
    assert cli.main([str(source), "-o", str(out), "--points", "--overwrite"]) == 0
    _, report = core.smooth_point_cloud(before, return_mesh=True)
    plural = sys.modules[ADDON + ".cli.command"].plural
    amount = f"{plural(report.rounds, 'round')} of {plural(report.iterations_per_round, 'step')}"
    assert amount in capsys.readouterr().out
    after, _ = import_positions(out / "points.ply")
    assert np.array_equal(after, core.smooth_point_cloud(before))


@pytest.mark.parametrize("invert", [False, True])
def test_points_keep_the_fixed_group(cli, tmp_path, invert):
    points = sphere_points()
    members = np.flatnonzero(points[:, 2] > 0.5)
    source = export_points(tmp_path / "scan.blend", points, group=members)
    out = tmp_path / "out"
    argv = [str(source), "-o", str(out), "--points", "--fixed-group", "Keep"] + (["--invert-group"] if invert else [])
    assert cli.main(argv) == 0
    after = blend_positions(out / "scan.blend")
    fixed = np.zeros(len(points), dtype=bool)
    fixed[members] = True
    fixed ^= invert
    assert np.array_equal(after[fixed], points[fixed])  # to the bit
    assert np.any(after[~fixed] != points[~fixed], axis=1).mean() > 0.9  # nearly all the others moved


def test_points_missing_group_fails_the_file(cli, capsys, tmp_path):
    source = export_points(tmp_path / "scan.blend", sphere_points(300), group=[0, 1, 2])
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out), "--points", "--fixed-group", "Nope"]) == 1
    assert f"{source}: FAILED: Object 'Points' has no vertex group 'Nope'" in capsys.readouterr().out
    assert not out.exists()


@pytest.mark.parametrize(
    "points, message",
    [
        (np.ones((100, 3), np.float32), "All 100 points of 'points' coincide: nothing to smooth"),
        (np.zeros((1, 3), np.float32), "'points' is a single point: nothing to smooth"),
    ],
)
def test_points_with_nothing_to_smooth_fail_without_output(cli, capsys, tmp_path, points, message):
    source = export_points(tmp_path / "points.ply", points)
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out), "--points"]) == 1
    text = capsys.readouterr().out
    assert f"{source}: FAILED: {message}" in text and "scan lines" not in text
    assert not out.exists()


# Data safety: nothing but the input itself under --in-place is ever replaced without --overwrite.


def snapshot(folder):
    return {name: digest(os.path.join(folder, name)) for name in sorted(os.listdir(folder))}


def test_in_place_with_another_format_never_replaces_unrelated_files(cli, capsys, tmp_path):
    source = export_noisy_sphere(tmp_path / "scan.ply")
    (tmp_path / "scan.obj").write_text("v 0 0 0\n")  # someone else's file, not this scan's
    (tmp_path / "scan.mtl").write_text("newmtl Precious\n")
    before = snapshot(tmp_path)
    assert cli.main([str(source), "--in-place", "--format", "obj"]) == 2
    err = capsys.readouterr().err
    assert f"would be replaced:\n  {tmp_path / 'scan.obj'}\n" in err and "or pass --overwrite" in err
    assert snapshot(tmp_path) == before
    # --overwrite replaces it; --in-place with --format writes beside the input and keeps it.
    assert cli.main([str(source), "--in-place", "--format", "obj", "--overwrite"]) == 0
    assert digest(source) == before["scan.ply"]
    assert (tmp_path / "scan.mtl").read_text() == "newmtl Precious\n"  # no .mtl is ever written
    smoothed, _ = import_positions(tmp_path / "scan.obj")
    original, _ = import_positions(source)
    assert len(smoothed) == len(original) and not np.allclose(smoothed, original, atol=1e-4)


def test_output_folder_results_are_not_replaced_without_overwrite(cli, capsys, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    good = export_noisy_sphere(folder / "good.ply")
    other = export_noisy_sphere(folder / "other.ply", seed=5)
    (folder / "good.obj").write_text("v 0 0 0\n")
    before = snapshot(folder)
    # other.ply could go ahead, but everything is checked before anything runs.
    assert cli.main([str(other), str(good), "-o", str(folder), "--format", "obj"]) == 2
    err = capsys.readouterr().err
    assert f"\n  {folder / 'good.obj'}\nchoose another -o OUTDIR, or pass --overwrite" in err
    assert snapshot(folder) == before
    assert cli.main([str(other), str(good), "-o", str(folder), "--format", "obj", "--overwrite"]) == 0
    assert sorted(os.listdir(folder)) == ["good.obj", "good.ply", "other.obj", "other.ply"]


def test_in_place_obj_never_writes_a_material_library(cli, capsys, tmp_path):
    source = export_noisy_sphere(tmp_path / "scan.obj")
    assert "mtllib scan.mtl" in source.read_text()
    library = (tmp_path / "scan.mtl").read_bytes()
    original, _ = import_positions(source)
    assert cli.main([str(source), "--in-place"]) == 0
    smoothed, _ = import_positions(source)
    assert not np.allclose(smoothed, original, atol=1e-4)
    assert sorted(os.listdir(tmp_path)) == ["scan.mtl", "scan.obj"]
    assert (tmp_path / "scan.mtl").read_bytes() == library
    assert "mtllib scan.mtl" in source.read_text()


def test_folder_inputs_skip_hidden_files(cli, capsys, tmp_path):
    scans = tmp_path / "scans"
    scans.mkdir()
    export_noisy_sphere(scans / "scan.ply")
    (scans / "._scan.ply").write_bytes(b"\x00\x05\x16\x07 macOS metadata")
    (scans / ".scan.hc_smooth-123.ply").write_bytes(b"ply\nformat ascii 1.0\n")  # a killed run's half-written file
    out = tmp_path / "out"
    assert cli.main([str(scans), "-o", str(out)]) == 0
    assert "1 of 1 files smoothed" in capsys.readouterr().out
    assert os.listdir(out) == ["scan.ply"]


def dead_pid():
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_stale_temporaries_of_killed_runs_are_removed(cli, capsys, tmp_path):
    source = export_noisy_sphere(tmp_path / "scan.ply")
    out = tmp_path / "out"
    out.mkdir()
    dead, alive = dead_pid(), os.getppid()
    stale = [f".scan.hc_smooth-{dead}.ply", f".old.hc_smooth-{dead}.obj.tmp", f".old.hc_smooth-{dead}.mtl"]
    kept = [
        f".scan.hc_smooth-{os.getpid()}.stl",
        f".other.hc_smooth-{alive}.ply",  # their runs may be writing
        ".notes.hc_smooth-abc.ply",
        ".keep",
        "mine.ply",
    ]  # not a pid, or not our pattern at all
    for name in stale + kept:
        (out / name).write_text("x")
    assert cli.main([str(source), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"removed {out / stale[0]}, left by an interrupted run" in text
    assert sorted(os.listdir(out)) == sorted(kept + ["scan.ply"])


@pytest.mark.parametrize("names", [("scan.ply", "scan.ply"), ("scan.ply", "./scan.ply"), ("scans", "scans/scan.ply")])
def test_an_input_named_twice_is_smoothed_once(cli, capsys, tmp_path, monkeypatch, names):
    monkeypatch.chdir(tmp_path)
    if names[0] == "scans":
        os.mkdir("scans")
        names = (names[0], os.path.join("scans", "scan.ply"))
    export_noisy_sphere(tmp_path / os.path.dirname(names[1]) / "scan.ply")
    assert cli.main([*names, "-o", "out"]) == 0
    text = capsys.readouterr().out
    assert "is named more than once" in text and "smoothing it once" in text
    assert "1 of 1 files smoothed" in text
    assert os.listdir("out") == ["scan.ply"]


@pytest.mark.parametrize("extra", [[], ["--points", "--steps-per-round", "200"]])
def test_divergent_parameters_fail_the_file_and_write_nothing(cli, capsys, tmp_path, extra):
    # Outside HC's convergence region (alpha > 0, beta > 0.5) the core raises instead of returning garbage.
    if extra:
        source = export_points(tmp_path / "scan.ply", sphere_points())
    else:
        source = export_noisy_sphere(tmp_path / "scan.ply")
    out = tmp_path / "out"
    argv = [str(source), "-o", str(out), "--alpha", "0", "--beta", "0"] + (extra or ["--iterations", "200"])
    assert cli.main(argv) == 1
    (line,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith("[1/1]")]
    assert f"{source}: FAILED:" in line and "alpha > 0 and beta > 0.5" in line
    assert not out.exists()


def test_blend_with_meshes_and_point_clouds_smooths_the_kind_asked_for(cli, capsys, tmp_path):
    points = sphere_points(500)
    export_points(tmp_path / "unused.ply", points)  # an empty scene holding the cloud "Points"
    mesh = noisy_sphere(name="Scan", seed=6)
    mesh_before = positions_of(mesh.data).copy()
    source = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    assert cli.main([str(source), "-o", str(tmp_path / "meshes")]) == 0
    assert "warning: left as they are: Points (point clouds: smooth them with --points)" in capsys.readouterr().out
    assert np.array_equal(blend_positions(tmp_path / "meshes" / "scene.blend"), points)
    assert not np.allclose(positions_of(bpy.data.objects["Scan"].data), mesh_before)
    assert cli.main([str(source), "-o", str(tmp_path / "clouds"), "--points"]) == 0
    assert "warning: left as they are: Scan (meshes: smooth them without --points)" in capsys.readouterr().out
    assert not np.allclose(blend_positions(tmp_path / "clouds" / "scene.blend"), points)
    assert np.array_equal(positions_of(bpy.data.objects["Scan"].data), mesh_before)


def test_slide_runs_the_sliding_default(cli, capsys, tmp_path):
    """The command line keeps vertices in place by default, as the operator does, and says so; --slide
    gives core's sliding default."""
    source = export_noisy_sphere(tmp_path / "scan.ply")
    before = import_positions(source)[0]
    for options, folder in (([], "kept"), (["--slide"], "slid")):
        assert cli.main([str(source), "-o", str(tmp_path / folder), *options]) == 0
        said = capsys.readouterr().out
        assert ("kept in place" in said) == (not options)
    kept, slid = (import_positions(tmp_path / folder / "scan.ply")[0] for folder in ("kept", "slid"))

    def slide(after):  # RMS along-surface part of each move; a sphere's normals are its directions
        normals = before / np.linalg.norm(before, axis=1, keepdims=True)
        move = (after - before).astype(np.float64)
        return np.sqrt(np.mean(np.sum((move - np.sum(move * normals, axis=1)[:, None] * normals) ** 2, axis=1)))

    assert len(kept) == len(slid) == len(before) and slide(kept) <= 0.4 * slide(slid)
