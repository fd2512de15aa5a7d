"""Scan files written by hand for the file tests: PLY with every kind of extra a scanner writes, OBJ
with materials and texture coordinates, STL with a header and attribute bytes. Plain NumPy."""

import numpy as np

PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4"}
PLY_TYPES.update({"float": "f4", "double": "f8"})


def octahedron(scale=1.0, noise=0.0, seed=0, subdivisions=2):
    """A closed triangle mesh around the origin (a subdivided octahedron pushed to a sphere), with noise."""
    positions = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    faces = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]], np.int64)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middle = len(positions) + inverse.ravel().reshape(3, -1).T
        positions = np.vstack([positions, positions[unique].mean(axis=1)])
        a, b, c = faces.T
        ab, bc, ca = middle.T
        faces = np.concatenate([np.stack(f, axis=1) for f in ([a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca])])
    positions /= np.linalg.norm(positions, axis=1, keepdims=True)
    rng = np.random.default_rng(seed)
    positions = scale * positions + noise * rng.normal(size=positions.shape)
    return positions, faces


def ply(elements, encoding="ascii", comments=("made by the tests",), obj_info=("scanner 1",)):
    """PLY bytes. ``elements``: [(name, [(property name, type or ("list", count type, item type)),
    ...], rows)], each row a list of values in property order (a list value is a sequence)."""
    header = ["ply", f"format {encoding} 1.0"]
    header += [f"comment {text}" for text in comments] + [f"obj_info {text}" for text in obj_info]
    for name, properties, rows in elements:
        header.append(f"element {name} {len(rows)}")
        for prop, kind in properties:
            header.append(
                f"property list {kind[1]} {kind[2]} {prop}" if isinstance(kind, tuple) else f"property {kind} {prop}"
            )
    header.append("end_header")
    out = [("\n".join(header) + "\n").encode()]  # pieces joined once: += on bytes copies every time
    order = "<" if encoding == "binary_little_endian" else ">"
    for _, properties, rows in elements:
        for row in rows:
            if encoding == "ascii":
                words = []
                for (_, kind), value in zip(properties, row):
                    if isinstance(kind, tuple):
                        words += [str(len(value)), *(_text(v, kind[2]) for v in value)]
                    else:
                        words.append(_text(value, kind))
                out.append((" ".join(words) + "\n").encode())
            else:
                for (_, kind), value in zip(properties, row):
                    if isinstance(kind, tuple):
                        out.append(np.array(len(value), order + PLY_TYPES[kind[1]]).tobytes())
                        out.append(np.array(value, order + PLY_TYPES[kind[2]]).tobytes())
                    else:
                        out.append(np.array(value, order + PLY_TYPES[kind]).tobytes())
    return b"".join(out)


def _text(value, kind):
    return repr(float(np.dtype(PLY_TYPES[kind]).type(value))) if kind in ("float", "double") else str(int(value))


def rich_ply(encoding, seed=0, normals=True):
    """A noisy closed mesh as a range-scan PLY: double positions? no, float; colours, flags, quality,
    a camera element, obj_info. Returns (bytes, positions, faces)."""
    positions, faces = octahedron(noise=0.02, seed=seed)
    rng = np.random.default_rng(seed)
    n, f = len(positions), len(faces)
    vertex_properties = [("x", "float"), ("y", "float"), ("z", "float")]
    if normals:
        vertex_properties += [("nx", "float"), ("ny", "float"), ("nz", "float")]
    vertex_properties += [
        ("red", "uchar"),
        ("green", "uchar"),
        ("blue", "uchar"),
        ("confidence", "double"),
        ("flags", "int"),
    ]
    radial = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    colours = rng.integers(0, 256, (n, 3))
    vertex_rows = [
        [
            *positions[i],
            *(radial[i] if normals else ()),
            *colours[i],
            rng.random() * 1e-3 + 0.1,
            int(rng.integers(-5, 5)),
        ]
        for i in range(n)
    ]
    face_properties = [
        ("vertex_indices", ("list", "uchar", "int")),
        ("red", "uchar"),
        ("green", "uchar"),
        ("blue", "uchar"),
    ]
    face_properties += [("flags", "int"), ("quality", "float")]
    face_rows = [
        [list(faces[i]), *rng.integers(0, 256, 3), int(rng.integers(0, 9)), float(rng.random())] for i in range(f)
    ]
    camera = [("view_px", "float"), ("view_py", "float"), ("view_pz", "float"), ("x_axisx", "double"), ("k1", "uint")]
    elements = [
        ("vertex", vertex_properties, vertex_rows),
        ("face", face_properties, face_rows),
        ("camera", camera, [[0.5, -1.25, 3.0, 1 / 3, 7]]),
    ]
    data = ply(elements, encoding)
    return data, positions.astype(np.float32).astype(np.float64), faces
