"""The scan-file readers (cli/formats) on broken files: valid small files of every format cut short,
with bytes flipped, with header counts inflated and (PLY) property types changed are read (and can be
written back), or refused with FormatError: no other exception, no warning, and never much more memory
than the valid file takes. Seeded: the same cases every run."""

import tracemalloc
import warnings

import numpy as np
import pytest
import scan_files
from test_cli_arguments import load

formats = load("cli.formats")
FormatError = formats.FormatError

CUTS = 40  # cut points per file (and every cut in the header)
FLIPS = 60  # flipped-byte variants per file
ENCODINGS = ["ascii", "binary_little_endian", "binary_big_endian"]
SLACK = 64 * 1024  # tracemalloc also counts the messages, tracebacks and Python objects of a refusal


def ply_file(encoding):
    """A coarse octahedron as PLY: float positions and normals, a double and a uchar per vertex, faces
    with a uchar list of ints, a char list and a float, and a one-record camera element."""
    positions, faces = scan_files.octahedron(noise=0.01, subdivisions=1)
    normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    vertex = [(name, "float") for name in ("x", "y", "z", "nx", "ny", "nz")] + [("quality", "double"), ("red", "uchar")]
    face = [("vertex_indices", ("list", "uchar", "int")), ("tags", ("list", "char", "uchar")), ("weight", "float")]
    elements = [
        ("vertex", vertex, [[*p, *n, 0.5, i] for i, (p, n) in enumerate(zip(positions.tolist(), normals.tolist()))]),
        ("face", face, [[f, [i % 3] * (i % 2), 0.25] for i, f in enumerate(faces.tolist())]),
        ("camera", [("k1", "uint"), ("focal", "double")], [[7, 1.5]]),
    ]
    return scan_files.ply(elements, encoding)


def obj_file():
    """A coarse octahedron as OBJ: v with colours, vt, vn, g and s lines, f in every corner form, negative
    indices, comments."""
    positions, faces = scan_files.octahedron(noise=0.01, subdivisions=1)
    n = len(positions)
    lines = ["# fuzz", "mtllib a.mtl", "o Part"]
    lines += [f"v {x!r} {y!r} {z!r} 0.5 0.5 0.5" for x, y, z in positions.tolist()]
    lines += [f"vt {i / n!r} 0.5" for i in range(n)] + [f"vn {x:.4f} {y:.4f} {z:.4f}" for x, y, z in positions]
    lines += ["g skin", "s 1"]
    forms = ["{0}", "{0}/{0}", "{0}//{0}", "{0}/{0}/{0}"]
    for i, face in enumerate(faces.tolist()):
        form = forms[i % len(forms)]
        numbers = [v + 1 if i % 2 else v - n for v in face]  # every other face counted back from the end
        lines.append("f " + " ".join(form.format(k) for k in numbers) + ("  # first" if i == 0 else ""))
    return ("\n".join(lines) + "\n").encode()


def stl_files():
    """The coarse octahedron as ASCII and binary STL (the binary's header starts with `solid`)."""
    positions, faces = scan_files.octahedron(noise=0.01, subdivisions=1)
    triangles = positions[faces].astype(np.float32)
    facets = "".join(
        "facet normal 0 0 1\n outer loop\n"
        + "".join(f"  vertex {x!r} {y!r} {z!r}\n" for x, y, z in t.tolist())
        + " endloop\nendfacet\n"
        for t in triangles
    )
    text = f"solid part\n{facets}endsolid part\n".encode()
    records = np.zeros(len(faces), formats.RECORD)
    records["corners"] = triangles
    records["attribute"] = np.arange(len(faces))
    binary = b"solid part, binary".ljust(80) + np.uint32(len(faces)).tobytes() + records.tobytes()
    return text, binary


def valid_files():
    ascii_stl, binary_stl = stl_files()
    files = {f"ply-{encoding}": (".ply", ply_file(encoding)) for encoding in ENCODINGS}
    files.update({"obj": (".obj", obj_file()), "stl-ascii": (".stl", ascii_stl), "stl-binary": (".stl", binary_stl)})
    return files


FILES = valid_files()


def header_length(ext, data):
    """The bytes before the records: a PLY header, a binary STL's 84 (0 for text)."""
    if ext == ".ply":
        return data.index(b"end_header") + len(b"end_header\n")
    return 84 if ext == ".stl" and formats.is_binary(data) else 0


def cut_variants(ext, data, rng):
    """The file cut at every point of its header and at CUTS points of its body."""
    head = header_length(ext, data)
    points = sorted(set(range(head)) | set(rng.integers(head, len(data), CUTS).tolist()))
    return [(f"cut at {point}", data[:point]) for point in points]


def flip_variants(data, rng):
    """FLIPS variants with one to three bytes changed: one bit, or a whole random byte."""
    variants = []
    for _ in range(FLIPS):
        changed = bytearray(data)
        where = rng.integers(0, len(data), rng.integers(1, 4))
        for at in where.tolist():
            changed[at] = changed[at] ^ (1 << int(rng.integers(0, 8))) if rng.random() < 0.5 else int(rng.integers(256))
        variants.append((f"bytes {where.tolist()} changed", bytes(changed)))
    return variants


def inflated_variants(ext, data):
    """The header's counts raised: a few more records, many more, and more than any file holds."""
    variants = []
    if ext == ".ply":
        head = data[: data.index(b"end_header")]
        for line in head.split(b"\n"):
            if line.startswith(b"element "):
                count = int(line.split()[2])
                for new in (count + 1, count * 1000, 2**31 - 1, 10**15):
                    bigger = line.rsplit(b" ", 1)[0] + b" %d" % new
                    variants.append((f"'{line.decode()}' as {new}", data.replace(line, bigger, 1)))
    elif ext == ".stl" and formats.is_binary(data):
        count = int(np.frombuffer(data, "<u4", 1, 80)[0])
        for new in (count + 1, count * 1000, 2**32 - 1):
            variants.append((f"facet count {new}", data[:80] + np.uint32(new).tobytes() + data[84:]))
    return variants


TYPES = ["char", "uchar", "short", "ushort", "int", "uint", "float", "double"]


def retyped_variants(ext, data, rng):
    """Each type word of a PLY header replaced by another type."""
    if ext != ".ply":
        return []
    end = data.index(b"end_header")
    words = data[:end].split(b" ")
    variants = []
    for i, word in enumerate(words):
        kind = word.split(b"\n")[0].decode()
        if kind in TYPES:
            new = rng.choice([other for other in TYPES if other != kind])
            changed = words[:i] + [word.replace(kind.encode(), new.encode(), 1)] + words[i + 1 :]
            variants.append((f"type {i} {kind} as {new}", b" ".join(changed) + data[end:]))
    return variants


def parse_measured(data, ext):
    """(mesh or None, FormatError or None, peak bytes held while parsing); a warning raises."""
    tracemalloc.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            mesh = formats.parse(data, ext)
        error = None
    except FormatError as refused:
        mesh, error = None, refused
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return mesh, error, peak


@pytest.mark.parametrize("name", sorted(FILES))
def test_broken_files_are_read_or_refused_cleanly_within_bounded_memory(name):
    ext, data = FILES[name]
    rng = np.random.default_rng(sum(map(ord, name)))
    formats.parse(data, ext)  # once before measuring: imports, compiled patterns
    mesh, error, need = parse_measured(data, ext)
    assert error is None and len(mesh.positions)
    variants = cut_variants(ext, data, rng) + flip_variants(data, rng) + inflated_variants(ext, data)
    variants += retyped_variants(ext, data, rng)
    refused = 0
    for what, variant in variants:
        try:
            mesh, error, peak = parse_measured(variant, ext)
        except Exception as other:  # anything but FormatError is a reader's bug
            raise AssertionError(f"{name}, {what}: {type(other).__name__}: {other}") from other
        assert peak <= 2 * need + SLACK, f"{name}, {what}: {peak} bytes held, the valid file needs {need}"
        if error is not None:
            refused += 1
            assert str(error), f"{name}, {what}: a refusal without a message"
            continue
        try:  # what is read can be written back
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                formats.updated(mesh, mesh.positions.astype(mesh.precision))
        except FormatError:
            pass
        except Exception as other:
            raise AssertionError(f"{name}, {what}: writing: {type(other).__name__}: {other}") from other
    assert refused > len(variants) // 3  # the cuts, at least, are refused
