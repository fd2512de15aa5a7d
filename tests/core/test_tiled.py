"""Scans larger than memory (cli/tiled.py, core/mesh/tiles.py, cli/formats/ply_blocks.py), without Blender: a
binary PLY smoothed in tiles is, byte for byte, the file the whole route writes; every byte but the
positions (and normals) stays; a failure or an interrupt leaves no output; what cannot run tiled is
refused with a message."""

import os
import subprocess
import sys

import numpy as np
import pytest
from test_cli_arguments import load

core = load("core")
tiled = load("cli.tiled")
formats = load("cli.formats")
ply = load("cli.formats.ply")
mesh_amount = load("core.mesh.amount")
in_place = load("core.mesh.in_place")
FormatError = formats.FormatError

# The options core_options gives for `--iterations K` (floats as Blender's properties hold them).
EXPLICIT = {
    "method": "hc",
    "alpha": float(np.float32(0.1)),
    "beta": float(np.float32(0.6)),
    "iterations": 4,
    "mode": "simultaneous",
    "tolerance": 0.0,
    "max_deviation": 0.0,
    "keep_sharp_edges": False,
    "sharpness_angle": float(np.float32(np.radians(30.0))),
    "keep_in_place": False,
    "weld": True,
    "border": "free",
}


def torus(rows, tube, noise=0.2, seed=0):
    """A torus of rows x tube vertices (grid order), noise ``noise`` x the edge length per coordinate."""
    u = np.linspace(0, 2 * np.pi, rows, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, tube, endpoint=False)[None, :]
    ring = 1.0 + 0.4 * np.cos(v)
    points = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), 0.4 * np.sin(v)), -1).reshape(-1, 3)
    points += np.random.default_rng(seed).normal(0, noise * 2 * np.pi * 0.4 / tube, points.shape)
    i, j = np.meshgrid(np.arange(rows), np.arange(tube), indexing="ij")
    a, b = i * tube + j, ((i + 1) % rows) * tube + j
    c, d = ((i + 1) % rows) * tube + (j + 1) % tube, i * tube + (j + 1) % tube
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return points, faces


def plate(side, noise=0.2, seed=0):
    """An open noisy square grid of side x side vertices (a border all round)."""
    i, j = np.meshgrid(np.arange(side), np.arange(side), indexing="ij")
    points = np.stack([i.ravel(), j.ravel(), np.zeros(side * side)], 1) / side
    points += np.random.default_rng(seed).normal(0, noise / side, points.shape)
    a = (i[:-1, :-1] * side + j[:-1, :-1]).ravel()
    faces = np.concatenate([np.stack([a, a + side, a + side + 1], 1), np.stack([a, a + side + 1, a + 1], 1)])
    return points, faces


def binary_ply(points, faces, normals=False, order="<", double=False):
    """PLY bytes with colours and a confidence per vertex, flags per face and a trailing element."""
    coordinate = order + ("f8" if double else "f4")
    fields = [("x", coordinate), ("y", coordinate), ("z", coordinate)]
    fields += [(name, order + "f4") for name in ("nx", "ny", "nz")] if normals else []
    fields += [("red", "u1"), ("green", "u1"), ("blue", "u1"), ("confidence", order + "f4")]
    vertices = np.zeros(len(points), fields)
    vertices["x"], vertices["y"], vertices["z"] = points.T
    vertices["red"], vertices["confidence"] = np.arange(len(points)) % 256, 0.5
    if normals:
        vertices["nz"] = 1.0
    records = np.zeros(len(faces), [("n", "u1"), ("i", order + "i4", (3,)), ("flags", order + "u2")])
    records["n"], records["i"], records["flags"] = 3, faces, 7
    kind = "double" if double else "float"
    header = ["ply", f"format binary_{'little' if order == '<' else 'big'}_endian 1.0", "comment tiled test"]
    header += [f"element vertex {len(points)}"] + [f"property {kind} {axis}" for axis in "xyz"]
    header += [f"property float {name}" for name in ("nx", "ny", "nz")] if normals else []
    header += ["property uchar red", "property uchar green", "property uchar blue", "property float confidence"]
    header += [f"element face {len(faces)}", "property list uchar int vertex_indices", "property ushort flags"]
    header += ["element camera 1", "property float view_px", "end_header"]
    return ("\n".join(header) + "\n").encode() + vertices.tobytes() + records.tobytes() + b"\x00\x00\x80\x3f"


def whole_bytes(data, options):
    """The whole route's result file: the file read whole, smoothed by core.MeshSmoother, written back."""
    mesh = formats.parse(data, ".ply")
    edges, triangles = tiled.surface_arrays(mesh.corners, mesh.sizes)
    result = core.MeshSmoother(mesh.positions.astype(mesh.precision), edges, faces=triangles, **options).run()
    return formats.updated(mesh, result)


def smooth_tiled(tmp_path, data, options, capacity, name="scan.ply"):
    source, target = tmp_path / name, tmp_path / "out" / name
    source.write_bytes(data)
    lines = []
    run = tiled.smooth_file(str(source), str(target), options, 8 << 30, say=lines.append, capacity=capacity)
    assert len(lines) == run.tiles * (2 if run.restoring else 1)  # a line per tile (and pass)
    return run, target.read_bytes()


@pytest.mark.parametrize(
    "case",
    [
        {},
        {"normals": True, "order": ">"},
        {"double": True, "method": "plain", "iterations": 6},
        {"max_deviation": 0.002, "iterations": 3},
    ],
    ids=["hc", "normals-big-endian", "double-laplacian", "deviation-limit"],
)
def test_tiled_equals_whole_bit_for_bit(tmp_path, case):
    layout = {key: case.pop(key) for key in ("normals", "order", "double") if key in case}
    points, faces = torus(400, 250)  # 100k vertices
    data = binary_ply(points, faces, **layout)
    options = {**EXPLICIT, **case}
    run, got = smooth_tiled(tmp_path, data, options, capacity=30_000)
    assert run.tiles >= 8
    assert got == whole_bytes(data, options)
    assert run.change.moved > 0.9 * len(points) and run.change.n_vertices == len(points)


@pytest.mark.parametrize("border", ["fixed", "curve"])
def test_open_borders_tiled_as_whole(tmp_path, border):
    points, faces = plate(200)
    data = binary_ply(points, faces)
    options = {**EXPLICIT, "border": border}
    run, got = smooth_tiled(tmp_path, data, options, capacity=15_000)
    assert run.tiles >= 4
    assert got == whole_bytes(data, options)


@pytest.mark.slow
def test_a_million_vertices_in_eight_tiles(tmp_path):
    points, faces = torus(1600, 625)  # 1M vertices
    data = binary_ply(points, faces)
    options = {**EXPLICIT, "iterations": 10}
    run, got = smooth_tiled(tmp_path, data, options, capacity=300_000)
    assert run.tiles >= 8
    assert got == whole_bytes(data, options)


def test_only_positions_change(tmp_path):
    points, faces = torus(300, 120)
    data = binary_ply(points, faces)
    _, got = smooth_tiled(tmp_path, data, EXPLICIT, capacity=12_000)
    before, after = ply.PlyFile(data), ply.PlyFile(got)
    assert len(got) == len(data)
    changed = np.flatnonzero(np.frombuffer(data, np.uint8) != np.frombuffer(got, np.uint8))
    x = before.vertex.where["x"]
    allowed = np.concatenate([x + k for k in range(12)])  # the three floats x, y, z of each record
    assert changed.size and np.isin(changed, allowed).all()
    assert not np.array_equal(after.positions, before.positions)


@pytest.mark.slow
def test_the_amount_chosen_once_runs_on_every_tile(tmp_path, monkeypatch):
    monkeypatch.setattr(mesh_amount, "WORK_BUDGET", 400_000)  # 4 iterations on these 100k vertices
    points, faces = torus(400, 250)
    data = binary_ply(points, faces)
    automatic = {**EXPLICIT, "alpha": core.AUTO, "beta": core.AUTO, "iterations": core.AUTO}
    automatic.update(max_deviation=core.AUTO, keep_in_place=core.AUTO)
    run, got = smooth_tiled(tmp_path, data, automatic, capacity=45_000)
    assert run.tiles >= 4 and run.amount.iterations == 4 and run.amount.capped and run.kept_in_place
    assert "fold guard" in run.notes[1] and "outlines" in run.notes[1] and "volume" not in run.notes[1]
    assert run.restoring and "volume back" in run.notes[-1]  # its volume change is negligible: no offset
    # Every tile ran the numbers chosen: the whole mesh run with them, within a millionth of its size.
    chosen = {**EXPLICIT, "alpha": 0.0, "beta": run.amount.beta, "iterations": 4, "keep_in_place": True}
    chosen["max_deviation"] = 4.0 * run.amount.sigma
    whole = ply.PlyFile(whole_bytes(data, chosen)).positions
    diagonal = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    result = ply.PlyFile(got).positions
    assert np.abs(result - whole).max() <= 1e-6 * diagonal
    # The report measures the volume of the closed torus, as the whole run's report does.
    measured = core.measure_change(points.astype(np.float32), result, faces)
    assert run.change.closed and run.change.volume_change == pytest.approx(measured.volume_change, abs=1e-6)


class Stop(Exception):
    pass


def stop_at_third_tile(monkeypatch, stop):
    """cli/tiled.py's smooth_tile raising ``stop`` (an exception class) on the third tile; returns the list of
    its calls (cleared: the count starts again)."""
    real, calls = tiled.smooth_tile, []

    def failing(*args):
        calls.append(1)
        if len(calls) == 3:
            raise stop()
        return real(*args)

    monkeypatch.setattr(tiled, "smooth_tile", failing)
    return calls


@pytest.mark.parametrize("stop", [Stop, KeyboardInterrupt])
def test_a_run_stopped_midway_leaves_no_output(tmp_path, monkeypatch, stop):
    points, faces = torus(300, 120)
    source, target = tmp_path / "scan.ply", tmp_path / "out" / "scan.ply"
    source.write_bytes(binary_ply(points, faces))
    calls = stop_at_third_tile(monkeypatch, stop)
    with pytest.raises(stop):
        tiled.smooth_file(str(source), str(target), EXPLICIT, 8 << 30, capacity=12_000)
    assert not (tmp_path / "out").exists()  # the folder made for it is gone too
    (tmp_path / "out").mkdir()
    target.write_bytes(b"an earlier result")
    calls.clear()
    with pytest.raises(stop):
        tiled.smooth_file(str(source), str(target), EXPLICIT, 8 << 30, capacity=12_000)
    assert os.listdir(tmp_path / "out") == ["scan.ply"] and target.read_bytes() == b"an earlier result"


def test_unsupported_layouts_are_refused(tmp_path):
    points, faces = torus(30, 20)
    path = tmp_path / "scan.ply"
    data = binary_ply(points, faces)
    path.write_bytes(data.replace(b"binary_little_endian", b"ascii", 1))
    with pytest.raises(FormatError, match="tiles read binary PLY or OBJ"):
        tiled.PlyBlocks(str(path))
    # A quad among triangles: the faces' records are no longer of one size.
    mixed = bytearray(data)
    body = data.index(b"end_header\n") + len(b"end_header\n")
    first_face = body + len(points) * (12 + 3 + 4)
    second_face = first_face + 1 + 12 + 2
    mixed[second_face] = 4
    path.write_bytes(bytes(mixed))
    with pytest.raises(FormatError, match="face 1 has 4 corners where the first has 3"):
        tiled.smooth_file(str(path), str(tmp_path / "out.ply"), EXPLICIT, 8 << 30, capacity=20_000)
    assert not (tmp_path / "out.ply").exists()
    listed = data.replace(b"property float confidence", b"property list uchar float confidence", 1)
    path.write_bytes(listed)
    with pytest.raises(FormatError, match="vertex records hold a list"):
        tiled.PlyBlocks(str(path))


@pytest.mark.parametrize(
    "option, words",
    [
        ({"keep_sharp_edges": True}, "Keep Sharp Edges cannot run in tiles"),
        ({"mode": "sequential"}, "sequential mode cannot run in tiles"),
        ({"tolerance": 0.001}, "--tolerance cannot run in tiles"),
    ],
)
def test_features_that_need_whole_parts_are_refused(tmp_path, option, words):
    points, faces = torus(30, 20)
    source = tmp_path / "scan.ply"
    source.write_bytes(binary_ply(points, faces))
    with pytest.raises(ValueError, match=words):
        tiled.smooth_file(str(source), str(tmp_path / "out.ply"), {**EXPLICIT, **option}, 8 << 30)
    assert not (tmp_path / "out.ply").exists()


def test_a_halo_larger_than_a_tile_is_refused(tmp_path):
    points, faces = torus(300, 120)
    source = tmp_path / "scan.ply"
    source.write_bytes(binary_ply(points, faces))
    with pytest.raises(ValueError, match="halo alone holds about .* raise it, or run fewer iterations"):
        options = {**EXPLICIT, "iterations": 60}
        tiled.smooth_file(str(source), str(tmp_path / "o.ply"), options, 8 << 30, capacity=12_000)


def test_boxes_own_every_point_once():
    rng = np.random.default_rng(0)
    points = rng.normal(size=(20_000, 3))
    points[:100] = np.round(points[:100], 1)  # points on the cuts
    boxes = core.tile_boxes(points, 1.0, points.min(axis=0), points.max(axis=0), 0.05, 3_000)
    owners = np.sum([box.owns(points) for box in boxes], axis=0)
    assert len(boxes) >= 8 and (owners == 1).all()
    assert max(box.reaches(points, 0.05).sum() for box in boxes) <= 3_000


def test_rings_read():
    assert core.tile_rings("hc", 10) == 20
    assert core.tile_rings("plain", 10) == 10
    assert core.tile_rings("hc", 3, keep_in_place=True, normals=True) == 6 + 1 + in_place._LAST + 1


arguments = load("cli.arguments")


@pytest.mark.parametrize(
    "text, size", [("4G", 4 << 30), ("500M", 500 << 20), ("1.5gb", int(1.5 * (1 << 30))), ("123456", 123456)]
)
def test_memory_limit_sizes(tmp_path, monkeypatch, text, size):
    monkeypatch.chdir(tmp_path)
    assert arguments.parse(["scan.ply", "-o", "out", "--memory-limit", text]).memory_limit == size
    assert arguments.parse(["scan.ply", "-o", "out"]).memory_limit is None


@pytest.mark.parametrize("text", ["lots", "0", "-4G", "inf", "4X"])
def test_bad_memory_limits(tmp_path, monkeypatch, text):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(arguments.UsageError, match=f"argument --memory-limit: {text} is not a (positive )?size"):
        arguments.parse(["scan.ply", "-o", "out", f"--memory-limit={text}"])


@pytest.mark.slow
def test_a_scattered_order_within_a_millionth(tmp_path):
    """The whole run renumbers a scattered mesh of 200k+ vertices (core.locality), its tiles do not: the
    sums round differently, far below a millionth of the size."""
    points, faces = torus(640, 400)  # 256k vertices
    order = np.random.default_rng(1).permutation(len(points))
    number = np.empty_like(order)
    number[order] = np.arange(len(order))
    points, faces = points[order], number[faces]
    data = binary_ply(points, faces)
    options = {**EXPLICIT, "iterations": 10}
    run, got = smooth_tiled(tmp_path, data, options, capacity=120_000)
    assert run.tiles >= 4
    whole = ply.PlyFile(whole_bytes(data, options)).positions
    diagonal = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    difference = np.abs(ply.PlyFile(got).positions - whole).max()
    assert 0 < difference <= 1e-6 * diagonal


def test_the_tiled_route_loads_no_blender_module():
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]); import test_cli_arguments as t; t.load('cli.tiled'); "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('bpy', 'mathutils', '_bpy')))"
    )
    here = os.path.dirname(__file__)
    done = subprocess.run([sys.executable, "-c", code, here], capture_output=True, text=True, cwd=here, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == "[]", done.stderr


def test_split_vertices_welded_alike(tmp_path):
    """A seam of split vertices (equal copies, as UV seams leave them): every tile welds the copies it holds
    as the whole run does."""
    rows, tube = 400, 250
    points, faces = torus(rows, tube)
    seam = np.arange(rows) * tube  # column 0 around the tube
    copies = len(points) + np.arange(rows)
    closing = (faces % tube == 0) & (np.roll(faces, 1, axis=1) % tube == tube - 1)  # reached from column tube-1
    faces = np.where(closing, copies[faces // tube], faces)
    points = np.concatenate([points, points[seam]])
    assert np.isin(copies, faces).all() and np.isin(seam, faces).all()  # both sides of the seam are used
    data = binary_ply(points, faces)
    run, got = smooth_tiled(tmp_path, data, EXPLICIT, capacity=30_000)
    assert run.tiles >= 8
    assert got == whole_bytes(data, EXPLICIT)
    result = ply.PlyFile(got).positions
    assert np.array_equal(result[seam], result[copies])  # the seam stayed closed
