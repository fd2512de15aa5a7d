"""An OBJ file smoothed in tiles (cli/formats/obj_blocks.py, cli/tiled.py), without Blender: with given numbers
it is, byte for byte, the file the whole route writes, whatever the face tokens, the `vn` layout and the
order of the lines; its scratch files are gone afterwards; what cannot run tiled (faces of different sizes,
STL's triangle soups) is refused with a message and nothing is written."""

import os

import numpy as np
import pytest
from test_cli_arguments import load
from test_tiled import EXPLICIT, stop_at_third_tile, torus

core = load("core")
tiled = load("cli.tiled")
formats = load("cli.formats")
obj_blocks = load("cli.formats.obj_blocks")
files = load("cli.files")
FormatError = formats.FormatError


def numbers(rows):
    return [b" ".join(b"%r" % value for value in row) for row in np.asarray(rows).tolist()]


def obj_text(points, faces, corners="v", normals="none", layout="plain"):
    """OBJ bytes of ``points`` and (f, k) ``faces``: ``corners`` the face tokens ("v", "v/vt/vn", "v//vn",
    "negative": -k counting back from the face); ``normals`` "vertex" (a vn per vertex), "shared" (7 vn used
    all over the mesh) or "none"; ``layout`` "plain", "mixed" (comments, groups, colours, vt, a material)
    or "split" (half the vertices after the faces that use them)."""
    n = len(points)
    v = [b"v " + text + (b" 0.5 0.25 1" if layout == "mixed" else b"") for text in numbers(points)]
    head = [b"# a scan", b"mtllib scan.mtl", b"o scan"] if layout == "mixed" else []
    extra = [b"vt 0.25 0.75", b"vt 0.5 0.5"] if layout == "mixed" or "vt" in corners else []
    count = {"vertex": n, "shared": 7, "none": 0}[normals]
    vn = [b"vn 0 0 1"] * count
    target = {"vertex": faces, "shared": np.arange(len(faces))[:, None] % 7 + 0 * faces}.get(normals)
    index = faces + 1 if corners != "negative" else faces - n  # all the vertices come before the faces then
    if corners == "v/vt/vn":
        tokens = [b"%d/%d/%d" % (i, 1 + i % 2, t + 1) for i, t in zip(index.ravel(), target.ravel())]
    elif corners == "v//vn":
        tokens = [b"%d//%d" % (i, t + 1) for i, t in zip(index.ravel(), target.ravel())]
    else:
        tokens = [b"%d" % i for i in index.ravel()]
    k = faces.shape[1]
    f = [b"f " + b" ".join(tokens[i : i + k]) for i in range(0, len(tokens), k)]
    if layout == "mixed":
        f[len(f) // 2 : len(f) // 2] = [b"g second", b"usemtl other", b"s 1", b"# half way"]
        head += [b"g first", b"usemtl skin"]
    if layout == "split":
        lines = v[: n // 2] + vn + extra + f + v[n // 2 :]
    else:
        lines = head + v + extra + vn + f
    return b"\r\n".join(lines) + b"\r\n" if layout == "mixed" else b"\n".join(lines) + b"\n"


def whole_bytes(data, options):
    """The whole route's result: the file read whole, smoothed by core.MeshSmoother, written back."""
    mesh = formats.parse(data, ".obj")
    edges, triangles = tiled.surface_arrays(mesh.corners, mesh.sizes)
    result = core.MeshSmoother(mesh.positions, edges, faces=triangles, **options).run()
    return formats.updated(mesh, result)


def smooth_tiled(tmp_path, data, options, capacity):
    source, target = tmp_path / "scan.obj", tmp_path / "out" / "scan.obj"
    source.write_bytes(data)
    lines = []
    run = tiled.smooth_file(str(source), str(target), options, 8 << 30, say=lines.append, capacity=capacity)
    assert len(lines) == run.tiles
    assert os.listdir(target.parent) == ["scan.obj"]  # the scratch files are gone
    return run, target.read_bytes()


def quads(faces):
    """The torus's triangle pairs (a, b, c), (a, c, d) as quads (a, b, c, d)."""
    half = len(faces) // 2
    return np.concatenate([faces[:half], faces[half:, 2:]], axis=1)


@pytest.mark.parametrize(
    "case",
    [
        {},
        {"corners": "v/vt/vn", "normals": "vertex", "layout": "mixed"},
        {"corners": "v//vn", "normals": "shared", "small": True},
        {"corners": "negative", "quads": True, "method": "plain", "iterations": 6},
        {"layout": "split", "max_deviation": 0.002, "iterations": 3},
    ],
    ids=["plain", "vt-vn-comments-groups-crlf", "shared-vn-small-pieces", "negative-quads-laplacian", "split"],
)
def test_tiled_obj_equals_whole_bit_for_bit(tmp_path, monkeypatch, case):
    if case.pop("small", False):  # many pieces of text and blocks of faces: their seams must not show
        monkeypatch.setattr(obj_blocks, "CHUNK", 100_000)
        monkeypatch.setattr(obj_blocks, "BLOCK", 7_000)
    points, faces = torus(400, 250)  # 100k vertices
    faces = quads(faces) if case.pop("quads", False) else faces
    layout = {key: case.pop(key) for key in ("corners", "normals", "layout") if key in case}
    data = obj_text(points, faces, **layout)
    options = {**EXPLICIT, **case}
    run, got = smooth_tiled(tmp_path, data, options, capacity=30_000)
    want = whole_bytes(data, options)
    assert run.tiles >= 8
    assert got == want
    assert run.change.moved > 0.9 * len(points) and run.change.n_vertices == len(points)
    if "normals" in layout:  # the vn were recomputed, not kept
        assert got.count(b"\nvn 0 0 1") < data.count(b"\nvn 0 0 1") / 2


def test_only_numbers_of_v_and_vn_change(tmp_path):
    points, faces = torus(300, 120)
    data = obj_text(points, faces, "v/vt/vn", "vertex", "mixed")
    _, got = smooth_tiled(tmp_path, data, EXPLICIT, capacity=12_000)
    before, after = data.split(b"\r\n"), got.split(b"\r\n")
    assert len(before) == len(after)
    changed = [(a, b) for a, b in zip(before, after) if a != b]
    assert len(changed) > len(points)  # the v and the vn lines
    for a, b in changed:
        assert a.split()[0] == b.split()[0] in (b"v", b"vn") and a.split()[4:] == b.split()[4:]


class Stop(Exception):
    pass


@pytest.mark.parametrize("stop", [Stop, KeyboardInterrupt])
def test_a_run_stopped_midway_leaves_nothing(tmp_path, monkeypatch, stop):
    points, faces = torus(300, 120)
    source, target = tmp_path / "scan.obj", tmp_path / "out" / "scan.obj"
    source.write_bytes(obj_text(points, faces, "v//vn", "vertex"))
    stop_at_third_tile(monkeypatch, stop)
    made, close = [], obj_blocks.ObjBlocks.close
    monkeypatch.setattr(obj_blocks.ObjBlocks, "close", lambda self: made.extend(self._made) or close(self))
    (tmp_path / "out").mkdir()
    target.write_bytes(b"an earlier result")
    with pytest.raises(stop):
        tiled.smooth_file(str(source), str(target), EXPLICIT, 8 << 30, capacity=12_000)
    assert os.listdir(tmp_path / "out") == ["scan.obj"] and target.read_bytes() == b"an earlier result"
    # The scratch files lay beside the target, named so that a later run removes them should this one be killed.
    assert len(made) >= 4 and {os.path.dirname(path) for path in made} == {str(tmp_path / "out")}
    assert all(files.TEMPORARY.match(os.path.basename(path)) for path in made)


def test_faces_of_different_sizes_are_refused(tmp_path):
    points, faces = torus(30, 20)
    data = obj_text(points, faces).replace(b"\nf ", b"\nf 1 ", 1)  # the first face a quad
    path = tmp_path / "scan.obj"
    path.write_bytes(data)
    with pytest.raises(FormatError, match=r"OBJ face 1 \(line 602\) has 3 corners where the first has 4"):
        tiled.smooth_file(str(path), str(tmp_path / "out" / "scan.obj"), EXPLICIT, 8 << 30, capacity=2_000)
    assert not (tmp_path / "out").exists()  # nor any scratch file


@pytest.mark.parametrize(
    "edit, words",
    [
        ((b"\nf 1 ", b"\nf 601 "), "vertex index 601 is out of range \\(the file has 600 in all\\)"),
        ((b"\nf 1 ", b"\nf -601 "), "vertex index -601 is out of range \\(the file has 600 at that point\\)"),
        ((b"\nv ", b"\nv nan "), "vertex 0 has a coordinate that is not a finite number"),
    ],
)
def test_bad_indices_and_coordinates_are_refused(tmp_path, edit, words):
    points, faces = torus(30, 20)
    path = tmp_path / "scan.obj"
    path.write_bytes((b"\n" + obj_text(points, faces)).replace(*edit, 1))
    with pytest.raises(FormatError, match=words):
        tiled.smooth_file(str(path), str(tmp_path / "out" / "scan.obj"), EXPLICIT, 8 << 30, capacity=2_000)
    assert not (tmp_path / "out").exists()


def test_stl_is_refused_plainly(tmp_path):
    path = tmp_path / "scan.stl"
    path.write_bytes(b"\0" * 84)
    with pytest.raises(FormatError, match="an STL file is a triangle soup: .* welding equal corners across the whole"):
        tiled.smooth_file(str(path), str(tmp_path / "out" / "scan.stl"), EXPLICIT, 8 << 30)
    assert not (tmp_path / "out").exists()
