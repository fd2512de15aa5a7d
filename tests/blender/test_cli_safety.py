"""What the command writes is exactly what was asked: through the command (and the bpy route), a scan
file's result differs from its input only in positions and normals; bad files, newer .blend files and
an -o onto a file are refused with nothing written; Ctrl+C stops a batch at any stage and leaves no
half-written file; a link replaced in place stays a link; a closed pipe ends quietly."""

import gzip
import importlib
import os
import pathlib
import signal
import subprocess
import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON
from bpy_route import install_documented

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "core"))
import scan_files  # noqa: E402  (tests/core: files written by hand)

ROUTE = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "hc_smooth_bpy.py"


@pytest.fixture
def cli(addon):
    return sys.modules[ADDON + ".cli"]


@pytest.fixture
def formats(addon):
    return importlib.import_module(ADDON + ".cli.formats")


def vertex_fields(formats, data):
    """A mask of the bytes of a binary PLY that hold vertex positions and normals."""
    mesh = formats.parse(data, ".ply")
    mask = np.zeros(len(data), dtype=bool)
    for name in ("x", "y", "z", "nx", "ny", "nz"):
        mask[mesh.vertex.where[name][:, None] + np.arange(4)] = True
    return mask


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_in_place_changes_only_positions_and_normals(cli, formats, tmp_path, encoding):
    data, positions, faces = scan_files.rich_ply(encoding)
    source = tmp_path / "scan.ply"
    source.write_bytes(data)
    assert cli.main([str(source), "--in-place", "--iterations", "3"]) == 0
    out = source.read_bytes()
    assert out[: out.index(b"end_header")] == data[: data.index(b"end_header")]
    smoothed = formats.parse(out, ".ply")
    assert not np.allclose(smoothed.positions, positions, atol=1e-4)
    np.testing.assert_array_equal(smoothed.corners.reshape(-1, 3), faces)
    if encoding == "ascii":
        before, after = data.splitlines(), out.splitlines()
        start = before.index(b"end_header") + 1 + len(positions)  # the face and camera lines
        assert before[start:] == after[start:]
        assert [line.split()[6:] for line in before[:start]] == [line.split()[6:] for line in after[:start]]
    else:
        mask = vertex_fields(formats, data)
        assert len(out) == len(data)
        assert np.array_equal(np.frombuffer(out, np.uint8)[~mask], np.frombuffer(data, np.uint8)[~mask])


def test_obj_with_a_material_library_keeps_it_and_every_other_line(cli, tmp_path):
    from test_cli_formats import RICH_MTL, rich_obj

    positions, faces = scan_files.octahedron(noise=0.01)
    source = tmp_path / "scan.obj"
    source.write_bytes(rich_obj(positions, faces))
    (tmp_path / "scan.mtl").write_bytes(RICH_MTL)
    (tmp_path / "colour.png").write_bytes(b"\x89PNG not really")
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out)]) == 0
    assert os.listdir(out) == ["scan.obj"]  # never a .mtl or a texture
    before, after = source.read_text().splitlines(), (out / "scan.obj").read_text().splitlines()
    assert [line for line in before if line[:2] not in ("v ", "vn")] == [
        line for line in after if line[:2] not in ("v ", "vn")
    ]
    assert cli.main([str(source), "--in-place"]) == 0
    assert (tmp_path / "scan.mtl").read_bytes() == RICH_MTL
    assert sorted(os.listdir(tmp_path)) == ["colour.png", "out", "scan.mtl", "scan.obj"]


def test_binary_stl_keeps_its_header_and_attribute_bytes(cli, formats, tmp_path):
    # noise the Automatic Amount finds and smooths (on the coarser octahedron with noise 0.01 it finds none,
    # and what it would take away is the shape: the part is left as it was, core.mesh.collapse)
    positions, faces = scan_files.octahedron(noise=0.03, subdivisions=3)
    records = np.zeros(len(faces), formats.RECORD)
    records["corners"] = positions[faces]
    records["attribute"] = np.arange(len(faces)) * 977 % 65536
    header = b"solid-looking header of a CAD tool".ljust(80, b"\x01")
    source = tmp_path / "scan.stl"
    source.write_bytes(header + np.uint32(len(faces)).tobytes() + records.tobytes())
    assert cli.main([str(source), "--in-place"]) == 0
    out = source.read_bytes()
    assert out[:84] == header + np.uint32(len(faces)).tobytes()
    after = np.frombuffer(out, formats.RECORD, offset=84)
    np.testing.assert_array_equal(after["attribute"], records["attribute"])
    assert not np.allclose(after["corners"], records["corners"], atol=1e-4)


PLY_TRIANGLE = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
FACE_LIST = b"element face 1\nproperty list uchar int vertex_indices\nend_header\n"
BINARY_TRIANGLE = PLY_TRIANGLE.replace(b"ascii", b"binary_little_endian")
NEGATIVE_FACE = np.int8(-3).tobytes() + np.arange(3, dtype="<i4").tobytes()  # a char list length of -3
STL_FACET = b"facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
# {name: (bytes, what the failure says)}
BAD_FILES = {
    "nan.ply": (PLY_TRIANGLE + FACE_LIST + b"0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n", "not a finite number"),
    "index.ply": (PLY_TRIANGLE + FACE_LIST + b"0 0 0\n1 1 0\n0 1 0\n3 0 1 7\n", "uses vertex 7"),
    "nan.obj": (b"v 0 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\n", "not a finite number"),
    "index.obj": (b"v 0 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 -4\n", "out of range"),
    "cut.stl": (b"solid part\n" + STL_FACET[: STL_FACET.index(b"endfacet")], "ASCII STL ends inside facet 0"),
    "cut-binary.stl": (b"solid part".ljust(80) + np.uint32(2).tobytes() + bytes(80), "binary STL cut short or invalid"),
    "bomb.ply": (
        BINARY_TRIANGLE.replace(b"vertex 3", b"vertex 100000000") + FACE_LIST + bytes(36) + NEGATIVE_FACE,
        "ends before its 100000000 vertex records",
    ),
    "negative.ply": (
        BINARY_TRIANGLE + FACE_LIST.replace(b"uchar", b"char") + bytes(36) + NEGATIVE_FACE,
        "vertex_indices list has a negative length (-3)",
    ),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_files_fail_and_nothing_is_written(cli, capfd, tmp_path, name):
    data, message = BAD_FILES[name]
    source = tmp_path / name
    source.write_bytes(data)
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 1
    out, err = capfd.readouterr()
    line = next(line for line in out.splitlines() if line.startswith("[1/1]"))
    assert "FAILED" in line and message in line and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    assert cli.main([str(source), "--in-place"]) == 1
    assert source.read_bytes() == data and os.listdir(tmp_path) == [name]


@pytest.mark.parametrize("ext", [".ply", ".blend"])
def test_a_name_of_250_characters_is_written(cli, tmp_path, ext):
    """The temporary a result is written to first is short: any name the folder takes works."""
    source = tmp_path / ("s" * (250 - len(ext)) + ext)
    if ext == ".blend":
        saved_blend(source)
    else:
        source.write_bytes(scan_files.rich_ply("binary_little_endian")[0])
    out = tmp_path / "out"
    assert cli.main([str(source), "-o", str(out), "--iterations", "2"]) == 0
    assert os.listdir(out) == [source.name]
    assert cli.main([str(source), "--in-place", "--iterations", "2"]) == 0
    assert sorted(os.listdir(tmp_path)) == sorted(["out", source.name])


def saved_blend(path, newer=False, packer=None):
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.mesh.primitive_ico_sphere_add()
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=False)
    data = bytearray(path.read_bytes())
    if newer:  # as Blender 9.99 would have written it
        if data.startswith(b"BLENDER17-"):  # Blender 5.0 and later: four digits after the header size and format
            data[13:17] = b"0999"
        else:
            data[9:12] = b"999"
    path.write_bytes(packer(bytes(data)) if packer else bytes(data))
    return path


@pytest.mark.parametrize("packer", [None, gzip.compress], ids=["plain", "gzip"])
def test_a_blend_from_a_newer_blender_is_refused(cli, capsys, tmp_path, packer):
    source = saved_blend(tmp_path / "scene.blend", newer=True, packer=packer)
    before = source.read_bytes()
    assert cli.main([str(source), "--in-place"]) == 1
    assert "saved by Blender 9.99, newer than this Blender" in capsys.readouterr().out
    assert source.read_bytes() == before
    assert cli.main([str(source), "-o", str(tmp_path / "out")]) == 1
    assert not (tmp_path / "out").exists()
    # Its own version passes.
    saved_blend(tmp_path / "own.blend", packer=packer)
    assert cli.main([str(tmp_path / "own.blend"), "-o", str(tmp_path / "out")]) == 0


def test_in_place_through_a_link_keeps_the_link(cli, capsys, tmp_path):
    data, positions, _ = scan_files.rich_ply("binary_little_endian")
    (tmp_path / "scans").mkdir()
    real = tmp_path / "scans" / "real.ply"
    real.write_bytes(data)
    link = tmp_path / "link.ply"
    link.symlink_to(real)
    assert cli.main([str(link), "--in-place"]) == 0
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_bytes() != data
    assert f"{link} -> {real}" in capsys.readouterr().out
    assert sorted(os.listdir(tmp_path / "scans")) == ["real.ply"]


def test_plurals(cli, capsys, tmp_path):
    source = tmp_path / "scan.ply"
    source.write_bytes(scan_files.rich_ply("ascii")[0])
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--iterations", "1"]) == 0
    text = capsys.readouterr().out
    assert "66 vertices, 1 iteration," in text and "1 iterations" not in text
    assert "1 of 1 files smoothed" in text


# The bpy route, as a user runs it (a subprocess).


@pytest.fixture(scope="module")
def route_user(extension_zip, tmp_path_factory):
    return install_documented(extension_zip, tmp_path_factory.mktemp("safety"))


def route(user, *args, **options):
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(user)}
    return subprocess.Popen(
        [sys.executable, str(ROUTE), "hc_smooth", *map(str, args)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **options,
    )


def test_usage_errors_on_the_route_name_the_route(route_user, tmp_path):
    run = route(route_user, "a.ply", "-o", tmp_path / "out", "--alpha", "2", cwd=tmp_path)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 2
    assert err.startswith("hc_smooth_bpy.py hc_smooth: error: argument --alpha") and "blender -b -c" not in err


def test_a_closed_pipe_ends_quietly(route_user, tmp_path):
    for name in ("a", "b", "c"):
        (tmp_path / f"{name}.ply").write_bytes(scan_files.rich_ply("binary_little_endian", seed=ord(name))[0])
    run = route(route_user, *(tmp_path / f"{n}.ply" for n in "abc"), "-o", tmp_path / "out", cwd=tmp_path)
    first = run.stdout.readline()  # as `| head -1` does: one line, then the reader is gone
    run.stdout.close()
    err = run.stderr.read()
    assert run.wait(timeout=300) == 0, err
    assert first.startswith("[1/3]")
    assert "Traceback" not in err and "BrokenPipe" not in err
    assert sorted(os.listdir(tmp_path / "out")) == ["a.ply", "b.ply", "c.ply"]  # the work was done


def big_scans(folder, names):
    """ASCII PLY scans large enough that reading, smoothing and writing each take a noticeable time."""
    positions, faces = scan_files.octahedron(noise=0.002, subdivisions=7)
    vertex = [("x", "float"), ("y", "float"), ("z", "float")]
    face = [("vertex_indices", ("list", "uchar", "int"))]
    data = scan_files.ply([("vertex", vertex, positions.tolist()), ("face", face, [[f] for f in faces.tolist()])])
    for name in names:
        (folder / name).write_bytes(data)
    return data


@pytest.mark.parametrize("stage", ["reading", "smoothing", "writing"])
def test_an_interrupt_stops_the_batch_at_any_stage(route_user, tmp_path, stage):
    names = ["a.ply", "b.ply", "c.ply"]
    data = big_scans(tmp_path, names)
    run = route(route_user, *names, "--in-place", "--verbose", cwd=tmp_path)
    seen = []
    for line in run.stdout:
        seen.append(line)
        if line.startswith(f"hc_smooth: {stage} ") and "b.ply" in line:
            run.send_signal(signal.SIGINT)
            break
    rest, err = run.communicate(timeout=300)
    assert run.returncode == 130, "".join(seen) + rest + err
    assert f"interrupted while {stage} b.ply" in err
    assert "1 file of 3 smoothed; 2 files left as they were (no partial output written)" in err
    assert (tmp_path / "a.ply").read_bytes() != data  # done before the interrupt
    assert (tmp_path / "b.ply").read_bytes() == data  # stopped: as it was
    assert (tmp_path / "c.ply").read_bytes() == data  # not started
    assert sorted(os.listdir(tmp_path)) == names  # no temporary left


def test_obj_groups_serve_as_fixed_group(cli, formats, tmp_path):
    positions, faces = scan_files.octahedron(noise=0.01)
    half = len(faces) // 2
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in positions.tolist()]
    lines += ["g Keep"] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces[:half]]
    lines += ["g Rest"] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces[half:]]
    source = tmp_path / "scan.obj"
    source.write_text("\n".join(lines) + "\n")
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--fixed-group", "Keep", "--iterations", "5"]) == 0
    after = formats.parse((tmp_path / "out" / "scan.obj").read_bytes(), ".obj").positions
    keep = np.unique(faces[:half])
    np.testing.assert_array_equal(after[keep], positions[keep])  # their lines as they were
    assert not np.allclose(np.delete(after, keep, axis=0), np.delete(positions, keep, axis=0), atol=1e-5)
