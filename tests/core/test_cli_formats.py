"""The command line's scan-file readers and writers (cli/formats), without Blender: a result is its input
with the positions and normals rewritten and nothing else; bad files are refused with a reason."""

import gzip
import os
import tracemalloc
import warnings

import numpy as np
import pytest
import scan_files
from test_cli_arguments import load

formats = load("cli.formats")
ply = load("cli.formats.ply")
FormatError = formats.FormatError
ENCODINGS = ["ascii", "binary_little_endian", "binary_big_endian"]


def smoothed(positions, seed=1):
    """Positions as a smoother returns them (float32), every vertex but the first moved."""
    rng = np.random.default_rng(seed)
    result = (positions + rng.normal(scale=0.01, size=positions.shape)).astype(np.float32)
    result[0] = positions[0]
    return result


def ply_values(data):
    """{element: {property: values}} of a PLY, read with the reader's header parser and the layout it finds."""
    mesh = ply.PlyFile(data)
    values = {}
    for element in mesh.elements:
        values[element.name] = {}
        for prop in element.properties:
            if prop.count_type is None:
                values[element.name][prop.name] = mesh._read(element, prop.name)
            else:
                values[element.name][prop.name] = mesh._read_list(element, prop.name)[0]
    return mesh, values


def header(data):
    return data[: data.index(b"end_header")]


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_ply_keeps_every_value_but_positions_and_normals(encoding):
    data, positions, faces = scan_files.rich_ply(encoding)
    mesh = formats.parse(data, ".ply")
    np.testing.assert_array_equal(mesh.positions, positions)
    np.testing.assert_array_equal(mesh.corners.reshape(-1, 3), faces)
    result = smoothed(positions)
    out = formats.updated(mesh, result)
    assert header(out) == header(data)  # comments, obj_info, every element and property as they were
    before, after = ply_values(data)[1], ply_values(out)[1]
    assert before.keys() == after.keys() == {"vertex", "face", "camera"}
    for element, properties in before.items():
        for name, values in properties.items():
            if element == "vertex" and name in ("x", "y", "z", "nx", "ny", "nz"):
                continue
            np.testing.assert_array_equal(after[element][name], values, err_msg=f"{element} {name}")
    written = np.stack([after["vertex"][a] for a in "xyz"], axis=1)
    np.testing.assert_array_equal(written.astype(np.float32), result)  # ASCII: the shortest text of each float
    normals = np.stack([after["vertex"][a] for a in ("nx", "ny", "nz")], axis=1)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-6)
    radial = result / np.linalg.norm(result, axis=1, keepdims=True)
    assert np.all(np.einsum("ij,ij->i", normals, radial) > 0.9)  # outward, the smoothed surface's
    assert not np.allclose(normals, np.stack([before["vertex"][a] for a in ("nx", "ny", "nz")], axis=1), atol=1e-3)
    if encoding != "ascii":
        # Byte for byte outside the position and normal fields of the vertex records.
        mesh_after = ply.PlyFile(out)
        changed = np.zeros(len(data), dtype=bool)
        for name in ("x", "y", "z", "nx", "ny", "nz"):
            changed[mesh_after.vertex.where[name][:, None] + np.arange(4)] = True
        assert len(out) == len(data)
        raw_before, raw_after = np.frombuffer(data, np.uint8), np.frombuffer(out, np.uint8)
        assert np.array_equal(raw_before[~changed], raw_after[~changed])


def test_ply_ascii_lines_keep_their_text_outside_the_rewritten_numbers():
    data, positions, _ = scan_files.rich_ply("ascii")
    out = formats.updated(formats.parse(data, ".ply"), smoothed(positions))
    before, after = data.decode().splitlines(), out.decode().splitlines()
    start = before.index("end_header") + 1
    assert len(before) == len(after) and before[:start] == after[:start]
    vertices = len(positions)
    for old, new in zip(before[start : start + vertices], after[start : start + vertices]):
        assert old.split()[6:] == new.split()[6:]  # colours, the double confidence and int flags as written
    assert before[start + vertices :] == after[start + vertices :]  # faces and the camera, line for line


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_ply_double_positions_stay_doubles_and_unmoved_vertices_stay_exact(encoding):
    positions, faces = scan_files.octahedron(noise=0.01)
    vertex = [("x", "double"), ("y", "double"), ("z", "double"), ("id", "uint")]
    rows = [[*p, i] for i, p in enumerate(positions)]
    data = scan_files.ply(
        [("vertex", vertex, rows), ("face", [("vertex_index", ("list", "uchar", "uint"))], [[list(f)] for f in faces])],
        encoding,
    )
    mesh = formats.parse(data, ".ply")
    np.testing.assert_array_equal(mesh.positions, positions)  # read at full precision
    result = smoothed(positions)
    out = formats.updated(mesh, result)
    _, after = ply_values(out)
    written = np.stack([after["vertex"][a] for a in "xyz"], axis=1)
    np.testing.assert_array_equal(written[0], positions[0])  # not moved: the stored double, not its float32
    np.testing.assert_array_equal(written[1:], result[1:].astype(np.float64))
    np.testing.assert_array_equal(after["vertex"]["id"], np.arange(len(positions)))
    assert formats.updated(mesh, positions.astype(np.float32)) == data  # nothing moved: the file as it was


def test_ply_binary_faces_of_mixed_sizes_and_lists_after_the_face_list():
    positions, faces = scan_files.octahedron(subdivisions=1)
    polygons = [list(faces[0]) + [5], *map(list, faces[1:])]  # one quad among triangles
    face = [
        ("vertex_indices", ("list", "uchar", "int")),
        ("texcoord", ("list", "uchar", "float")),
        ("quality", "float"),
    ]
    rows = [[p, [0.25] * (2 * len(p)), float(i)] for i, p in enumerate(polygons)]
    for encoding in ENCODINGS:
        data = scan_files.ply(
            [("vertex", [("x", "float"), ("y", "float"), ("z", "float")], positions.tolist()), ("face", face, rows)],
            encoding,
        )
        mesh = formats.parse(data, ".ply")
        assert mesh.sizes.tolist() == [4] + [3] * (len(faces) - 1)
        assert mesh.corners.tolist() == [i for p in polygons for i in p]
        _, values = ply_values(formats.updated(mesh, smoothed(positions)))
        np.testing.assert_array_equal(values["face"]["quality"], np.arange(len(polygons)))


def test_ply_point_cloud_keeps_its_normals():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(50, 3))
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    properties = [(a, "float") for a in ("x", "y", "z", "nx", "ny", "nz")]
    data = scan_files.ply([("vertex", properties, np.hstack([points, normals]).tolist())], "binary_little_endian")
    mesh = formats.parse(data, ".ply")
    assert mesh.sizes.size == 0
    out = formats.updated(mesh, smoothed(mesh.positions))
    _, values = ply_values(out)
    np.testing.assert_array_equal(
        np.stack([values["vertex"][a] for a in ("nx", "ny", "nz")], axis=1), normals.astype(np.float32)
    )


RICH_MTL = b"""# a scanner's material
newmtl skin
Ka 0.1 0.1 0.1
Kd 0.8 0.7 0.6
Tf 0.9 0.9 0.9
map_Ka -s 2 2 1 ambient.png
map_Kd -s 1 1 1 -o 0.5 0.5 0 colour.png
"""


def rich_obj(positions, faces, normals=True):
    """An OBJ with a material library, groups, smoothing groups, texture coordinates, vertex colours,
    comments, v/vt/vn corners and negative (relative) indices in the second half."""
    lines = ["# scanned", "mtllib scan.mtl", "o Scan"]
    lines += [f"v {x!r} {y!r} {z!r} 0.5 0.25 1" for x, y, z in positions.tolist()]
    lines += [f"vt {i / len(positions)!r} 0.5" for i in range(len(positions))]
    if normals:
        radial = positions / np.linalg.norm(positions, axis=1, keepdims=True)
        lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in radial]
    lines += ["g skin", "usemtl skin", "s 1"]
    half = len(faces) // 2
    n = len(positions)
    for i, face in enumerate(faces):
        if i < half:
            corners = [f"{v + 1}/{v + 1}/{v + 1}" if normals else f"{v + 1}/{v + 1}" for v in face]
        else:  # counted back from the end: -1 is the last v (and vt, vn) before this line
            corners = [f"{v - n}/{v - n}/{v - n}" if normals else f"{v - n}//"[:0] + f"{v - n}" for v in face]
        lines.append("f " + " ".join(corners) + ("  # a comment" if i == 0 else ""))
    return ("\n".join(lines) + "\n").encode()


@pytest.mark.parametrize("normals", [True, False])
def test_obj_keeps_every_line_but_positions_and_normals(normals):
    positions, faces = scan_files.octahedron(noise=0.01)
    data = rich_obj(positions, faces, normals)
    mesh = formats.parse(data, ".obj")
    np.testing.assert_allclose(mesh.positions, positions, rtol=0, atol=0)
    np.testing.assert_array_equal(mesh.corners.reshape(-1, 3), faces)
    assert mesh.has_normals == normals
    result = smoothed(positions)
    out = formats.updated(mesh, result)
    before, after = data.decode().splitlines(), out.decode().splitlines()
    assert len(before) == len(after)
    for old, new in zip(before, after):
        if old.startswith("v "):
            assert old.split()[4:] == new.split()[4:]  # the vertex colours as written
        elif old.startswith("vn "):
            assert len(new.split()) == 4
        else:
            assert old == new
    again = formats.parse(out, ".obj")
    np.testing.assert_array_equal(again.positions.astype(np.float32), result)
    assert after[3] == before[3]  # the first vertex did not move: its line as it was
    if normals:
        radial = result / np.linalg.norm(result, axis=1, keepdims=True)
        assert np.all(np.einsum("ij,ij->i", again.normals, radial) > 0.9)
        np.testing.assert_allclose(np.linalg.norm(again.normals, axis=1), 1, atol=1e-6)


def test_obj_flat_normals_follow_their_face():
    """A vn used by one face only (flat shading) becomes that face's normal."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]], float)
    data = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2//2 4//2 3//2\n"
    mesh = formats.parse(data, ".obj")
    result = positions.astype(np.float32)
    result[0, 2] = -0.25
    out = formats.parse(formats.updated(mesh, result), ".obj")
    first = np.cross(result[1] - result[0], result[2] - result[0])
    np.testing.assert_allclose(out.normals[0], first / np.linalg.norm(first), atol=1e-6)
    np.testing.assert_array_equal(out.normals[1], [0, 0, 1])  # its face did not move: as it was


@pytest.mark.parametrize("binary", [True, False])
def test_stl_keeps_header_and_attribute_bytes(binary):
    positions, faces = scan_files.octahedron(noise=0.01)
    triangles = positions[faces].astype(np.float32)
    if binary:
        records = np.zeros(len(faces), formats.RECORD)
        records["corners"] = triangles
        records["normal"] = [0, 0, 1]
        records["attribute"] = np.arange(len(faces)) * 977 % 65536  # colours of a VisCAM/SolidView STL
        data = (
            b"solid-looking header from a CAD tool, 80 bytes".ljust(80, b"\x07")
            + np.uint32(len(faces)).tobytes()
            + records.tobytes()
        )
    else:
        facets = [
            "  facet normal 0 0 1\n    outer loop\n"
            + "".join(f"      vertex {x!r} {y!r} {z!r}\n" for x, y, z in t.tolist())
            + "    endloop\n  endfacet\n"
            for t in triangles
        ]
        data = ("solid scan\n" + "".join(facets) + "endsolid scan\n").encode()
    mesh = formats.parse(data, ".stl")
    assert len(mesh.positions) == len(positions)  # corners merged by position
    np.testing.assert_array_equal(mesh.positions[mesh.corners], triangles.reshape(-1, 3).astype(np.float64))
    result = smoothed(mesh.positions)
    out = formats.updated(mesh, result)
    again = formats.parse(out, ".stl")
    np.testing.assert_array_equal(again.positions[again.corners].astype(np.float32), result[mesh.corners])
    if binary:
        assert out[:84] == data[:84]
        after = np.frombuffer(out, formats.RECORD, offset=84)
        np.testing.assert_array_equal(after["attribute"], records["attribute"])
        expected = np.cross(
            after["corners"][:, 1] - after["corners"][:, 0], after["corners"][:, 2] - after["corners"][:, 0]
        )
        expected /= np.linalg.norm(expected, axis=1, keepdims=True)
        np.testing.assert_allclose(after["normal"], expected, atol=1e-5)
    else:
        before_lines, after_lines = data.decode().splitlines(), out.decode().splitlines()
        assert [line for line in before_lines if "vertex" not in line and "normal" not in line] == [
            line for line in after_lines if "vertex" not in line and "normal" not in line
        ]


PLY_HEAD = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
FACE_HEAD = b"element face 1\nproperty list uchar int vertex_indices\nend_header\n"
STL_FACET = b"facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n"


@pytest.mark.parametrize(
    "ext, data, message",
    [
        (
            ".ply",
            PLY_HEAD + b"end_header\n0 0 0\nnan 1 0\n0 1 0\n",
            "vertex 1 has a coordinate that is not a finite number (nan)",
        ),
        (
            ".ply",
            PLY_HEAD + FACE_HEAD + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
            "face 0 uses vertex 3, but the file has 3 vertices",
        ),
        (
            ".ply",
            PLY_HEAD + FACE_HEAD + b"0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
            "face 0 uses vertex -1",
        ),
        (
            ".ply",
            PLY_HEAD.replace(b"float", b"int") + b"end_header\n0 0 0\n1 0 0\n0 1 0\n",
            "is not a float or double",
        ),
        (
            ".ply",
            PLY_HEAD + b"end_header\n0 0 0\n1 0\n0 1 0\n",
            "vertex record 1 has 2 values where the header says 3",
        ),
        (
            ".ply",
            PLY_HEAD.replace(b"ascii", b"binary_little_endian") + b"end_header\n",
            "ends",
        ),
        (
            ".obj",
            b"v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n",
            "vertex 1 has a coordinate that is not a finite number (inf)",
        ),
        (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "vertex index 4 is out of range (the file has 3 in all)"),
        (
            ".obj",
            b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n",
            "vertex index -3 is out of range (the file has 2 at that point)",
        ),
        (".obj", b"f -1 -2 -3\n" + b"v 0 0 0\n" * 178, "index -1 is out of range (the file has 0 at that point)"),
        (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0 (OBJ indices start at 1)"),
        (".obj", b"v 0 0 zero\n", "'zero' is not a number"),
        (".stl", b"solid a\n" + STL_FACET[: STL_FACET.index(b"endfacet")], "ASCII STL ends inside facet 0"),
        (".stl", b"solid a\n" + STL_FACET * 2, "no 'endsolid' after its last facet"),
        (".stl", b"solid a\n" + STL_FACET.replace(b"outer", b"outre") + b"endsolid a\n", "'outre' where 'outer'"),
    ],
    ids=[
        "ply-nan",
        "ply-index",
        "ply-negative",
        "ply-int-positions",
        "ply-short-line",
        "ply-truncated",
        "obj-inf",
        "obj-index",
        "obj-relative",
        "obj-relative-before-any-vertex",
        "obj-zero",
        "obj-word",
        "stl-cut-after-endloop",
        "stl-without-endsolid",
        "stl-misspelt",
    ],
)
def test_bad_files_are_refused_with_the_reason(ext, data, message):
    with pytest.raises(FormatError, match=None) as raised:
        formats.parse(data, ext)
    assert message in str(raised.value)


def test_binary_nan_is_refused():
    positions, faces = scan_files.octahedron()
    positions[5, 1] = np.nan
    data = scan_files.ply(
        [
            ("vertex", [("x", "float"), ("y", "float"), ("z", "float")], positions.tolist()),
            ("face", [("vertex_indices", ("list", "uchar", "int"))], [[list(f)] for f in faces]),
        ],
        "binary_big_endian",
    )
    with pytest.raises(FormatError, match="vertex 5 has a coordinate that is not a finite number"):
        formats.parse(data, ".ply")
    records = np.zeros(2, formats.RECORD)
    records["corners"][1, 2, 0] = np.inf
    with pytest.raises(FormatError, match="not a finite number"):
        formats.parse(bytes(80) + np.uint32(2).tobytes() + records.tobytes(), ".stl")


@pytest.mark.parametrize("source", [".ply", ".obj", ".stl"])
@pytest.mark.parametrize("target", [".ply", ".obj", ".stl"])
def test_conversions_carry_the_smoothed_geometry(source, target):
    positions, faces = scan_files.octahedron(noise=0.01)
    data = {
        ".ply": scan_files.rich_ply("ascii")[0],
        ".obj": rich_obj(positions, faces),
        ".stl": formats.converted(formats.parse(rich_obj(positions, faces), ".obj"), positions, ".stl"),
    }[source]
    mesh = formats.parse(data, source)
    result = smoothed(mesh.positions)
    out = formats.parse(formats.converted(mesh, result, target), target)
    triangles = result[mesh.corners.reshape(-1, 3)]
    np.testing.assert_array_equal(out.positions[out.corners.reshape(-1, 3)].astype(np.float32), triangles)
    assert out.has_normals == (source != ".stl" or target == ".stl")  # vertex normals only from vertex normals


files = load("cli.files")


@pytest.mark.parametrize(
    "start, version",
    [
        (b"BLENDER-v405REND", (4, 5)),  # 64-bit pointers, little endian, Blender 4.5
        (b"BLENDER_V279REND", (2, 79)),
        (b"BLENDER17-01v0502REND", (5, 2)),  # the header of Blender 5.0 and later
        (b"PK\x03\x04 not a blend", None),
    ],
)
def test_blend_header_versions(tmp_path, start, version):
    assert files.header_version(start) == version
    plain, packed = tmp_path / "plain.blend", tmp_path / "packed.blend"
    plain.write_bytes(start + bytes(100))
    packed.write_bytes(gzip.compress(start + bytes(100)))
    assert files.blend_version(str(plain)) == files.blend_version(str(packed)) == version
    try:
        import zstandard
    except ImportError:  # no way to read a zstd header here: the command asks Blender after opening
        zstandard = None
    squeezed = tmp_path / "squeezed.blend"
    squeezed.write_bytes(
        b"\x28\xb5\x2f\xfd" + bytes(60) if zstandard is None else zstandard.compress(start + bytes(100))
    )
    assert files.blend_version(str(squeezed)) == (None if zstandard is None else version)


def test_newer_blend_files_are_refused():
    files.check_blend_version((4, 5), (4, 5, 3))
    files.check_blend_version((4, 2), (5, 2, 0))
    files.check_blend_version(None, (4, 5, 3))  # unknown here: checked again once Blender has opened it
    with pytest.raises(files.FileError, match="saved by Blender 5.2, newer than this Blender"):
        files.check_blend_version((5, 2), (4, 5, 3))


def test_obj_groups_name_the_vertices_of_their_faces():
    data = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\ng left both\nf 1 2 3\ng right both\nf 2 4 3\ng\nf 3 4 5\n"
    mesh = formats.parse(data, ".obj")
    groups = mesh.groups({"left", "right", "both", "absent"})
    assert {name: members.tolist() for name, members in groups.items()} == {
        "left": [0, 1, 2],
        "right": [1, 2, 3],
        "both": [0, 1, 2, 3],
    }


FAR = np.array([500000.0, 5000000.0, 250.0])  # a georeferenced scan: single precision steps by 0.5 here


def far_files():
    """{ext: bytes} of a noisy unit sphere at FAR, as an OBJ with exact digits and a binary double PLY."""
    positions, faces = scan_files.octahedron(noise=0.01)
    positions = positions + FAR
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in positions.tolist()] + [
        f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces
    ]
    vertex = [("x", "double"), ("y", "double"), ("z", "double")]
    face = [("vertex_indices", ("list", "uchar", "int"))]
    double = scan_files.ply(
        [("vertex", vertex, positions.tolist()), ("face", face, [[f] for f in faces.tolist()])], "binary_little_endian"
    )
    return positions, {".obj": ("\n".join(lines) + "\n").encode(), ".ply": double}


@pytest.mark.parametrize("source", [".obj", ".ply"])
@pytest.mark.parametrize("target", [".ply", ".obj"])
def test_conversions_keep_double_precision(source, target):
    """--format writes float64 positions so that they read back exactly: PLY double properties, OBJ digits."""
    positions, data = far_files()
    mesh = formats.parse(data[source], source)
    assert mesh.precision == np.float64
    result = positions + np.random.default_rng(2).normal(scale=0.001, size=positions.shape)
    out = formats.parse(formats.converted(mesh, result, target), target)
    np.testing.assert_array_equal(out.positions, result)
    assert len(np.unique(out.positions[:, 1])) == len(np.unique(result[:, 1]))
    single = result.astype(np.float32)  # a float32 result is written in single precision
    written = formats.converted(mesh, single, target)
    assert (b"property float x" in written) == (target == ".ply")
    np.testing.assert_array_equal(formats.parse(written, target).positions.astype(np.float32), single)


@pytest.mark.parametrize("source", [".obj", ".ply"])
def test_conversion_to_stl_refuses_what_single_precision_would_move(source):
    positions, data = far_files()
    mesh = formats.parse(data[source], source)
    with pytest.raises(FormatError, match="STL file holds single-precision coordinates.*write PLY or OBJ"):
        formats.converted(mesh, positions, ".stl")
    near = positions - FAR  # near the origin, single precision moves it by far less than its size
    out = formats.parse(formats.converted(mesh, near, ".stl"), ".stl")
    np.testing.assert_allclose(out.positions[out.corners], near[mesh.corners], rtol=0, atol=1e-6)


def small_ply(encoding):
    """A tetrahedron as PLY bytes: vertices with a double, faces with a char list."""
    positions, faces = np.eye(4, 3), [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]]
    vertex = [("x", "float"), ("y", "float"), ("z", "float"), ("quality", "double")]
    face = [("vertex_indices", ("list", "char", "int"))]
    data = scan_files.ply(
        [("vertex", vertex, [[*p, 1.0] for p in positions]), ("face", face, [[f] for f in faces])], encoding
    )
    return data


def peak_bytes(function):
    """The most memory ``function()`` held at once (NumPy's arrays included), and what it raised."""
    tracemalloc.start()
    try:
        function()
    except FormatError as error:
        return tracemalloc.get_traced_memory()[1], error
    finally:
        tracemalloc.stop()
    return None, None


@pytest.mark.parametrize("element", ["vertex", "face"])
@pytest.mark.parametrize("encoding", ENCODINGS)
def test_counts_the_file_cannot_hold_are_refused_before_anything_is_allocated(encoding, element):
    """A few hundred bytes claiming 100 million records: refused at once, not after gigabytes of arrays."""
    bomb = small_ply(encoding).replace(f"element {element} 4".encode(), f"element {element} 100000000".encode())
    peak, error = peak_bytes(lambda: formats.parse(bomb, ".ply"))
    assert f"ends before its 100000000 {element} records" in str(error) and "wrong count in the header" in str(error)
    assert peak < 100_000


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_a_negative_list_length_is_refused_with_the_reason(encoding):
    data = small_ply(encoding)
    body = data.index(b"end_header\n") + len(b"end_header\n")
    if encoding == "ascii":
        lines = data[body:].split(b"\n")
        lines[4] = b"-" + lines[4]  # the first face: -3 0 1 2
        bad = data[:body] + b"\n".join(lines)
    else:
        face = body + 4 * (3 * 4 + 8)  # past the vertex records (three floats and a double)
        bad = data[:face] + np.int8(-3).tobytes() + data[face + 1 :]
    with pytest.raises(FormatError, match=r"PLY face record 0: its vertex_indices list has a negative length \(-3\)"):
        formats.parse(bad, ".ply")


@pytest.mark.parametrize("cut", ["truncated", "count"])
def test_a_broken_binary_stl_with_a_solid_header_is_called_binary(cut):
    records = np.zeros(4, formats.RECORD)
    records["corners"] = np.eye(3)
    data = b"solid part, as some CAD tools head a binary STL".ljust(80) + np.uint32(4).tobytes() + records.tobytes()
    assert formats.parse(data, ".stl").binary
    bad = data[:-7] if cut == "truncated" else data[:80] + np.uint32(9).tobytes() + data[84:]
    with pytest.raises(FormatError, match="binary STL cut short or invalid: its header counts"):
        formats.parse(bad, ".stl")


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_only_an_end_header_line_ends_the_header(encoding):
    positions, faces = scan_files.octahedron(noise=0.01)
    vertex, face = [("x", "float"), ("y", "float"), ("z", "float")], [("vertex_indices", ("list", "uchar", "int"))]
    elements = [("vertex", vertex, positions.tolist()), ("face", face, [[f] for f in faces.tolist()])]
    data = scan_files.ply(elements, encoding, comments=("exported by a tool that writes end_header last",))
    mesh = formats.parse(data, ".ply")
    np.testing.assert_array_equal(mesh.positions, positions.astype(np.float32))
    np.testing.assert_array_equal(mesh.corners.reshape(-1, 3), faces)
    result = smoothed(mesh.positions)
    out = formats.updated(mesh, result, {"hc_deviation": np.arange(len(positions), dtype=np.float32)})
    assert b"comment exported by a tool that writes end_header last\n" in out
    _, values = ply_values(out)
    np.testing.assert_array_equal(np.stack([values["vertex"][a] for a in "xyz"], axis=1).astype(np.float32), result)
    np.testing.assert_array_equal(values["vertex"]["hc_deviation"], np.arange(len(positions)))


def test_temporary_names_are_short_and_recognised(tmp_path):
    target = str(tmp_path / ("a" * 246 + ".ply"))  # a 250-character name: valid, with no room to spare
    first, second = files.temporary_path(target), files.temporary_path(target)
    assert first != second and os.path.dirname(first) == str(tmp_path)
    name = os.path.basename(first)
    assert name.startswith(".hc_smooth-") and name.endswith(".ply") and len(name) < 40
    assert files.TEMPORARY.match(name).group(1) == str(os.getpid())
    with open(first, "wb"):  # the folder takes the name
        pass
    assert files.TEMPORARY.match(".scan.hc_smooth-123.ply").group(1) == "123"  # the longer names of older runs
    assert files.TEMPORARY.match(".notes.hc_smooth-abc.ply") is None


def test_a_signalling_nan_is_refused_without_a_numpy_warning():
    """A float32 signalling NaN warns when cast to float64: the readers refuse it as any NaN, quietly."""
    signalling = np.array([0x7F800001], "<u4").view("<f4")[0]
    records = np.zeros(2, formats.RECORD)
    records["corners"][1, 2, 0] = signalling
    stl = bytes(80) + np.uint32(2).tobytes() + records.tobytes()
    ply_data = scan_files.ply(
        [("vertex", [("x", "float"), ("y", "float"), ("z", "float")], [[0, 0, 0]])], "binary_little_endian"
    )
    ply_data = ply_data[:-12] + signalling.tobytes() + bytes(8)
    for data, ext in ((stl, ".stl"), (ply_data, ".ply")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(FormatError, match="not a finite number"):
                formats.parse(data, ext)


def test_a_property_line_without_a_type_is_refused():
    with pytest.raises(FormatError, match="PLY header: bad property 'property'"):
        formats.parse(PLY_HEAD + b"property\nend_header\n0 0 0\n1 0 0\n0 1 0\n", ".ply")


@pytest.mark.parametrize("ext", [".ply", ".stl"])
def test_text_beyond_single_precision_is_refused(ext):
    """ASCII float properties and ASCII STL are single precision: 1e39 would become inf when smoothed."""
    if ext == ".ply":
        data = PLY_HEAD + b"end_header\n0 0 0\n1e39 1 0\n0 1 0\n"
    else:
        data = b"solid a\n" + STL_FACET.replace(b"vertex 1 0 0", b"vertex 1e39 0 0") + b"endsolid a\n"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(FormatError, match=r"vertex 1 has a coordinate \(1e\+39\) beyond the single-precision"):
            formats.parse(data, ext)


@pytest.mark.parametrize("length", [2.5, np.nan, np.inf, 1e30])
def test_a_float_list_length_must_be_a_whole_number(length):
    head = PLY_HEAD.replace(b"ascii", b"binary_little_endian") + FACE_HEAD.replace(b"uchar", b"float")
    data = head + bytes(36) + np.float32(length).tobytes() + np.arange(3, dtype="<i4").tobytes()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no 'invalid value encountered in cast' on the way
        with pytest.raises(FormatError, match="PLY face vertex_indices list length: .* is not a whole number"):
            formats.parse(data, ".ply")
