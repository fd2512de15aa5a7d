"""The command's files: a result comes back in its input's layout (encoding, normals, materials,
colours), Blender's own messages stay off the progress lines, and a run that wrote nothing leaves
no output folder behind."""

import os
import struct
import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, faces_of, noisy_sphere, positions_of, select_only

PLY_TYPES = {
    "char": "i1",
    "uchar": "u1",
    "short": "i2",
    "ushort": "u2",
    "int": "i4",
    "uint": "u4",
    "float": "f4",
    "double": "f8",
}


@pytest.fixture
def cli(addon):
    return sys.modules[ADDON + ".cli"]


def sphere_arrays(seed=0):
    """Positions, triangles and the true (radial) normals of a noisy icosphere."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere(seed=seed)
    positions = positions_of(obj.data).copy()
    radial = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    return positions, np.array(faces_of(obj.data)), radial.astype(np.float32)


def write_ply(path, columns, faces=None, encoding="ascii"):
    """A PLY written by hand: ``columns`` is a list of (property name, PLY type, values) for the vertices."""
    count = len(columns[0][2])
    header = ["ply", f"format {encoding} 1.0", f"element vertex {count}"]
    header += [f"property {kind} {name}" for name, kind, _ in columns]
    if faces is not None:
        header += [f"element face {len(faces)}", "property list uchar int vertex_indices"]
    header.append("end_header")
    with open(path, "wb") as file:
        file.write(("\n".join(header) + "\n").encode())
        if encoding == "ascii":
            for i in range(count):
                file.write((" ".join(repr(value[i].item()) for _, _, value in columns) + "\n").encode())
            for face in faces if faces is not None else ():
                file.write((" ".join(map(str, [len(face), *face])) + "\n").encode())
            return path
        endian = "<" if encoding == "binary_little_endian" else ">"
        dtype = np.dtype([(name, endian + PLY_TYPES[kind]) for name, kind, _ in columns])
        records = np.empty(count, dtype)
        for name, _, values in columns:
            records[name] = values
        file.write(records.tobytes())
        for face in faces if faces is not None else ():
            file.write(struct.pack(endian + "B" + "i" * len(face), len(face), *face))
    return path


def read_ply(path):
    """(format word, vertex property names, {name: values}) of a PLY whose first element is the vertices."""
    data = open(path, "rb").read()
    end = data.index(b"end_header") + len(b"end_header\n")
    lines = data[:end].decode().splitlines()
    encoding = next(line.split()[1] for line in lines if line.startswith("format "))
    count = next(int(line.split()[2]) for line in lines if line.startswith("element vertex"))
    properties, element = [], None
    for line in lines:
        words = line.split()
        if words[0] == "element":
            element = words[1]
        elif words[0] == "property" and element == "vertex":
            properties.append((words[2], words[1]))
    names = [name for name, _ in properties]
    if encoding == "ascii":
        rows = np.array([row.split() for row in data[end:].decode().splitlines()[:count]], dtype=np.float64)
        return encoding, names, {name: rows[:, i] for i, name in enumerate(names)}
    endian = "<" if encoding == "binary_little_endian" else ">"
    dtype = np.dtype([(name, endian + PLY_TYPES[kind]) for name, kind in properties])
    records = np.frombuffer(data, dtype, count, offset=end)
    return encoding, names, {name: records[name] for name in names}


def columns_of(values, names):
    return np.stack([values[name] for name in names], axis=1).astype(np.float64)


def surface_normals(path):
    """The vertex normals Blender computes for the surface in ``path`` (the file's own normals dropped)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.wm.ply_import(filepath=str(path))
    mesh = bpy.data.objects[0].data
    if "custom_normal" in mesh.attributes:
        mesh.attributes.remove(mesh.attributes["custom_normal"])
    normals = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertex_normals.foreach_get("vector", normals)
    return normals.reshape(-1, 3)


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
@pytest.mark.parametrize("normals", [True, False])
def test_ply_keeps_its_encoding_and_normals(cli, tmp_path, encoding, normals):
    positions, faces, radial = sphere_arrays()
    columns = [(axis, "float", positions[:, i]) for i, axis in enumerate("xyz")]
    if normals:  # a scanner's normals, not those of the noisy surface
        columns += [(axis, "float", radial[:, i]) for i, axis in enumerate(("nx", "ny", "nz"))]
    source = write_ply(tmp_path / "scan.ply", columns, faces, encoding)
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 0
    result = tmp_path / "out" / "scan.ply"
    written, names, values = read_ply(result)
    assert written == encoding
    assert names[:3] == ["x", "y", "z"]
    assert ({"nx", "ny", "nz"} <= set(names)) == normals
    assert not any(name.startswith("normal_") for name in names)
    smoothed = columns_of(values, "xyz")
    assert smoothed.shape == positions.shape and not np.allclose(smoothed, positions, atol=1e-3)
    if normals:  # the smoothed surface's normals, not the input's carried along
        written_normals = columns_of(values, ("nx", "ny", "nz"))
        np.testing.assert_allclose(written_normals, surface_normals(result), atol=1e-5)
        assert not np.allclose(written_normals, radial, atol=1e-3)


# A georeferenced scan: a unit sphere at UTM-like coordinates, where single precision steps by 0.5.
FAR = np.array([512345.0, 4123456.0, 250.0])


def far_sphere():
    """(positions in doubles, far from the origin, and triangles) of a noisy icosphere of radius 1."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere(sigma=0.02)
    return positions_of(obj.data).astype(np.float64) + FAR, np.array(faces_of(obj.data))


def far_file(folder, kind, positions, faces):
    """The far sphere as an OBJ with every digit ("obj") or a binary PLY with double positions ("ply-double")."""
    if kind == "obj":
        source = folder / "scan.obj"
        lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in positions.tolist()] + [
            f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces
        ]
        source.write_text("\n".join(lines) + "\n")
        return source
    columns = [(axis, "double", positions[:, i]) for i, axis in enumerate("xyz")]
    return write_ply(folder / "scan.ply", columns, faces, "binary_little_endian")


@pytest.mark.parametrize("kind", ["ply-double", "obj"])
def test_files_are_smoothed_in_the_precision_they_store(cli, addon, tmp_path, kind):
    """Doubles stay doubles: the run is core's on the file's float64 arrays, bit for bit, with the add-on's
    options; through single precision the sphere would be shattered into 0.5-unit steps."""
    positions, faces = far_sphere()
    source = far_file(tmp_path, kind, positions, faces)
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 0
    out = tmp_path / "out" / source.name
    if kind == "obj":
        smoothed = np.array([line.split()[1:] for line in out.read_text().splitlines() if line.startswith("v ")], float)
    else:
        smoothed = columns_of(read_ply(out)[2], "xyz")
    jobs, settings_spec = sys.modules[ADDON + ".jobs.mesh"], sys.modules[ADDON + ".settings_spec"]
    options = jobs.core_options(settings_spec.MeshSettings())
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    expected = sys.modules[ADDON + ".core"].MeshSmoother(positions, edges, faces=faces, **options).run()
    assert expected.dtype == np.float64
    np.testing.assert_array_equal(smoothed, expected)
    radius = np.linalg.norm(smoothed - FAR, axis=1)
    assert np.abs(radius - 1.0).max() < 0.1  # on the sphere: no single-precision steps


@pytest.mark.parametrize("kind, fmt", [("ply-double", "obj"), ("obj", "ply")])
def test_format_change_keeps_double_precision(cli, capsys, tmp_path, kind, fmt):
    """--format writes the smoothed doubles so that they read back exactly; STL, single precision only,
    refuses a mesh that far from the origin."""
    formats = sys.modules[ADDON + ".cli.formats"]
    source = far_file(tmp_path, kind, *far_sphere())
    assert cli.main([str(source), "-o", str(tmp_path / "same"), "--iterations", "3"]) == 0
    assert cli.main([str(source), "-o", str(tmp_path / "other"), "--iterations", "3", "--format", fmt]) == 0
    same = formats.read(str(tmp_path / "same" / source.name)).positions
    other = formats.read(str(tmp_path / "other" / f"scan.{fmt}")).positions
    np.testing.assert_array_equal(other, same)
    assert len(np.unique(other[:, 1])) > len(other) // 2  # not a handful of single-precision steps
    capsys.readouterr()
    assert cli.main([str(source), "-o", str(tmp_path / "stl"), "--iterations", "3", "--format", "stl"]) == 1
    assert "STL file holds single-precision coordinates" in capsys.readouterr().out
    assert not (tmp_path / "stl").exists()


def test_ply_keeps_colours_uvs_and_other_properties(cli, tmp_path):
    positions, faces, _ = sphere_arrays(seed=1)
    count = len(positions)
    rng = np.random.default_rng(2)
    colours = rng.integers(0, 256, size=(count, 3), dtype=np.uint8)
    uv = ((positions[:, :2] + 1) / 2).astype(np.float32)  # one UV per vertex: no seams to split at
    quality = rng.random(count).astype(np.float32)
    columns = [(axis, "float", positions[:, i]) for i, axis in enumerate("xyz")]
    columns += [(name, "uchar", colours[:, i]) for i, name in enumerate(("red", "green", "blue"))]
    columns += [("s", "float", uv[:, 0]), ("t", "float", uv[:, 1]), ("quality", "float", quality)]
    source = write_ply(tmp_path / "scan.ply", columns, faces, "binary_little_endian")
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 0
    _, names, values = read_ply(tmp_path / "out" / "scan.ply")
    # With UVs Blender's exporter writes the vertices in face order: match them through the unique quality.
    order = np.argsort(values["quality"])[np.argsort(np.argsort(quality))]
    np.testing.assert_array_equal(values["quality"][order], quality)
    # Byte for byte: Blender's sRGB conversion there and back would darken each colour by a step.
    assert np.array_equal(columns_of(values, ("red", "green", "blue"))[order], colours)
    np.testing.assert_array_equal(columns_of(values, "st")[order], uv.astype(np.float64))
    assert not np.allclose(columns_of(values, "xyz")[order], positions, atol=1e-3)


@pytest.mark.parametrize("normals", [True, False])
def test_ply_point_cloud_keeps_its_normals(cli, tmp_path, normals):
    rng = np.random.default_rng(3)
    directions = rng.normal(size=(1000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    points = (directions + rng.normal(scale=0.01, size=directions.shape)).astype(np.float32)
    columns = [(axis, "float", points[:, i]) for i, axis in enumerate("xyz")]
    if normals:
        columns += [(axis, "float", directions[:, i].astype(np.float32)) for i, axis in enumerate(("nx", "ny", "nz"))]
    source = write_ply(tmp_path / "points.ply", columns)
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--points"]) == 0
    written, names, values = read_ply(tmp_path / "out" / "points.ply")
    assert written == "ascii"
    assert ({"nx", "ny", "nz"} <= set(names)) == normals
    assert not any(name.startswith("normal_") for name in names)  # not renamed by the exporter
    if normals:  # points have no surface to recompute them from: the scanner's are kept
        np.testing.assert_allclose(columns_of(values, ("nx", "ny", "nz")), directions, atol=1e-6)
    assert not np.allclose(columns_of(values, "xyz"), points, atol=1e-4)


def export_sphere(path, **options):
    """A noisy sphere written with Blender's exporter for ``path``'s format, with ``options``."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere()
    select_only(obj)
    getattr(bpy.ops.wm, path.suffix[1:] + "_export")(filepath=str(path), export_selected_objects=True, **options)
    return obj


def import_positions(path):
    bpy.ops.wm.read_homefile(use_empty=True)
    getattr(bpy.ops.wm, path.suffix[1:] + "_import")(filepath=str(path))
    return positions_of(bpy.data.objects[0].data).copy()


def stl_is_binary(path):
    data = open(path, "rb").read()
    return len(data) >= 84 and len(data) == 84 + 50 * struct.unpack("<I", data[80:84])[0]


@pytest.mark.parametrize("kind", ["ascii", "binary", "binary starting with solid"])
def test_stl_keeps_its_encoding(cli, tmp_path, kind):
    source = tmp_path / "scan.stl"
    export_sphere(source, ascii_format=kind == "ascii")
    if kind == "binary starting with solid":  # some CAD tools write binary STL with such a header
        data = bytearray(source.read_bytes())
        data[:5] = b"solid"
        source.write_bytes(bytes(data))
    assert stl_is_binary(source) == (kind != "ascii")
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 0
    result = tmp_path / "out" / "scan.stl"
    assert stl_is_binary(result) == (kind != "ascii")
    if kind == "ascii":
        assert result.read_bytes().startswith(b"solid") and b"facet normal" in result.read_bytes()
    assert not np.allclose(import_positions(result), import_positions(source), atol=1e-3)


def obj_lines(path, keyword):
    return [line for line in open(path).read().splitlines() if line.split()[:1] == [keyword]]


@pytest.mark.parametrize("normals", [True, False])
@pytest.mark.parametrize("materials", [True, False])
def test_obj_gains_no_normals_and_no_material_library_is_written(cli, tmp_path, normals, materials):
    source = tmp_path / "scan.obj"
    export_sphere(source, export_normals=normals, export_materials=materials)
    assert bool(obj_lines(source, "vn")) == normals and bool(obj_lines(source, "mtllib")) == materials
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out)]) == 0
    result = out / "scan.obj"
    assert bool(obj_lines(result, "vn")) == normals
    assert obj_lines(result, "mtllib") == obj_lines(source, "mtllib")  # the line as it was
    assert os.listdir(out) == ["scan.obj"]  # the .mtl and textures are the user's to copy
    assert not np.allclose(import_positions(result), import_positions(source), atol=1e-3)


def test_obj_keeps_vertex_colours(cli, tmp_path):
    source = tmp_path / "scan.obj"
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere()
    colours = np.random.default_rng(4).random((len(obj.data.vertices), 4)).astype(np.float32)
    colours[:, 3] = 1
    obj.data.color_attributes.new("Color", "FLOAT_COLOR", "POINT").data.foreach_set("color", colours.ravel())
    select_only(obj)
    bpy.ops.wm.obj_export(filepath=str(source), export_selected_objects=True, export_colors=True)
    assert {len(line.split()) for line in obj_lines(source, "v")} == {7}  # v x y z r g b
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 0
    before = np.array([line.split()[4:] for line in obj_lines(source, "v")], dtype=float)
    after = np.array([line.split()[4:] for line in obj_lines(tmp_path / "out" / "scan.obj", "v")], dtype=float)
    np.testing.assert_allclose(after, before, atol=1e-4)  # OBJ writes 4 decimals


def test_format_change_keeps_normals_and_takes_the_exporters_encoding(cli, tmp_path):
    positions, faces, radial = sphere_arrays()
    columns = [(axis, "float", positions[:, i]) for i, axis in enumerate("xyz")]
    columns += [(axis, "float", radial[:, i]) for i, axis in enumerate(("nx", "ny", "nz"))]
    source = write_ply(tmp_path / "scan.ply", columns, faces, "ascii")
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out), "--format", "obj"]) == 0
    assert obj_lines(out / "scan.obj", "vn") and not obj_lines(out / "scan.obj", "mtllib")  # a PLY has no materials
    assert os.listdir(out) == ["scan.obj"]
    assert cli.main([str(out / "scan.obj"), "-o", str(tmp_path / "back"), "--format", "ply"]) == 0
    written, names, _ = read_ply(tmp_path / "back" / "scan.ply")
    assert written == "binary_little_endian" and {"nx", "ny", "nz"} <= set(names)


def test_blender_messages_stay_off_the_progress_lines(cli, capfd, tmp_path):
    ply, obj = tmp_path / "a.ply", tmp_path / "b.obj"
    export_sphere(ply)
    export_sphere(obj)
    capfd.readouterr()
    assert cli.main([str(ply), str(obj), "-o", str(tmp_path / "out")]) == 0
    captured = capfd.readouterr()
    lines = captured.out.splitlines()
    assert [line.split()[0] for line in lines[:2]] == ["[1/2]", "[2/2]"]
    assert lines[2].split() == ["file", "vertices", "smoothing", "time", "change", "result"]
    assert [line.split()[0] for line in lines[3:5]] == [str(ply), str(obj)]
    assert lines[5:] == ["2 of 2 files smoothed"]
    assert captured.err == ""


def test_blender_messages_of_a_failed_file_follow_its_line(cli, capfd, tmp_path):
    good = tmp_path / "a.ply"
    export_sphere(good)
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "whole.blend"))
    broken = tmp_path / "broken.blend"
    broken.write_bytes((tmp_path / "whole.blend").read_bytes()[:3000])  # cut short: Blender cannot read it
    capfd.readouterr()
    assert cli.main([str(broken), str(good), "-o", str(tmp_path / "out")]) == 1
    lines = capfd.readouterr().out.splitlines()
    failed = next(i for i, line in enumerate(lines) if line.startswith("[1/2]"))
    assert "FAILED: could not open the .blend file" in lines[failed]
    following = lines[failed + 1 : lines.index(next(line for line in lines if line.startswith("[2/2]")))]
    assert following and all(line.startswith("  blender: ") for line in following)
    assert any("broken.blend" in line for line in following)  # Blender's own report
    assert not any("blender:" in line for line in lines[lines.index(next(x for x in lines if x.startswith("[2/2]"))) :])


def test_a_run_that_writes_nothing_leaves_no_output_folder(cli, capsys, tmp_path):
    broken = tmp_path / "broken.ply"
    broken.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\n")
    out = tmp_path / "out" / "nested"
    assert cli.main([str(broken), str(tmp_path / "missing.stl"), "-o", str(out)]) == 1
    assert os.listdir(tmp_path) == ["broken.ply"]
    # A folder that existed before the run is not the run's to remove.
    (tmp_path / "kept").mkdir()
    assert cli.main([str(broken), "-o", str(tmp_path / "kept")]) == 1
    assert os.listdir(tmp_path / "kept") == []


def test_a_failed_write_removes_the_folder_it_created(cli, capsys, tmp_path, monkeypatch):
    source = tmp_path / "scan.obj"
    export_sphere(source)
    replace = os.replace

    def disk_full(*args):
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(cli.files.os, "replace", disk_full)  # the temporary is written, then cannot be moved
    out = tmp_path / "new"
    assert cli.main([str(source), "-o", str(out)]) == 1
    monkeypatch.undo()
    assert "FAILED: disk full (simulated)" in capsys.readouterr().out
    assert not out.exists()
    # With one result written, the folder stays with that result only.
    other = tmp_path / "other.obj"
    export_sphere(other)
    monkeypatch.setattr(
        cli.files.os, "replace", lambda path, target: disk_full() if "other" in target else replace(path, target)
    )
    assert cli.main([str(source), str(other), "-o", str(out)]) == 1
    monkeypatch.undo()
    assert sorted(os.listdir(out)) == ["scan.obj"]


def test_user_errors_print_no_traceback(cli, capfd, tmp_path, monkeypatch):
    source = tmp_path / "scan.ply"
    export_sphere(source)
    (tmp_path / "taken").write_text("a file where the output folder should be")
    capfd.readouterr()
    assert cli.main([str(source), "-o", str(tmp_path / "taken")]) == 2  # before any file is read
    captured = capfd.readouterr()
    assert f"-o {tmp_path / 'taken'}: the output folder is a file, not a folder" in captured.err
    assert "Traceback" not in captured.err
    assert cli.main([str(source), "-o", str(tmp_path / "taken" / "deeper")]) == 2
    assert "lies under" in capfd.readouterr().err
    # A folder input that cannot be listed is a bad command line, not a bug.
    scans = tmp_path / "scans"
    scans.mkdir()

    def refused(path):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(os, "scandir", refused)
    assert cli.main([str(scans), "-o", str(tmp_path / "out")]) == 2
    monkeypatch.undo()
    captured = capfd.readouterr()
    assert f"{scans}: Permission denied" in captured.err and "Traceback" not in captured.err
