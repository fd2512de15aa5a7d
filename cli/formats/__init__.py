"""The scan files the command line reads and writes itself (PLY, OBJ, STL), in NumPy, without Blender.

``read`` gives a file's mesh (positions, faces) and refuses what cannot be smoothed (NaN or infinite
coordinates, face indices out of range). ``updated`` gives the file's bytes with the smoothed positions
written in and the normals the file carries recomputed for the smoothed surface; every other byte is
kept (see ply.py, obj.py, stl.py). ``converted`` writes the smoothed geometry in another format. Both
take ``added``, {name: one float per vertex} (the deviation map), which only a PLY file holds.
"""

import os

import numpy as np

from ... import core
from . import normals as normal_maths
from .obj import ObjFile
from .ply import PlyFile
from .stl import RECORD, StlFile, is_binary
from .tokens import FormatError, number_texts

READERS = {".ply": PlyFile, ".obj": ObjFile, ".stl": StlFile}
__all__ = ["FormatError", "read", "parse", "updated", "converted", "is_binary"]


def read(path):
    """The file at ``path`` parsed (PlyFile, ObjFile or StlFile); raises FormatError or OSError."""
    ext = os.path.splitext(path)[1].lower()
    with open(path, "rb") as file:
        data = file.read()
    return parse(data, ext)


def parse(data, ext):
    mesh = READERS[ext](data)
    check(mesh)
    return mesh


def check(mesh):
    """Refuse coordinates that are not finite or that the file's precision cannot hold, and faces that name a
    vertex the file does not have."""
    bad = ~np.isfinite(mesh.positions)
    if bad.any():
        rows = np.flatnonzero(bad.any(axis=1))
        value = mesh.positions[rows[0]][bad[rows[0]]][0]
        others = (
            f" (and {len(rows) - 1} more vertices)"
            if len(rows) > 2
            else " (and 1 more vertex)"
            if len(rows) == 2
            else ""
        )
        raise FormatError(
            f"vertex {rows[0]} has a coordinate that is not a finite number ({value}){others}; nothing was written"
        )
    beyond = np.abs(mesh.positions) > np.finfo(mesh.precision).max  # text read as double, kept as float
    if beyond.any():
        row = int(np.flatnonzero(beyond.any(axis=1))[0])
        raise FormatError(
            f"vertex {row} has a coordinate ({mesh.positions[row][beyond[row]][0]:g}) beyond the single-precision "
            "range the file keeps its positions in; nothing was written"
        )
    if mesh.corners.size:
        outside = (mesh.corners < 0) | (mesh.corners >= len(mesh.positions))
        if outside.any():
            corner = int(np.flatnonzero(outside)[0])
            face = int(np.searchsorted(np.cumsum(mesh.sizes), corner, side="right"))
            count = len(mesh.positions)
            has = f"{count} vertices (0 to {count - 1})" if count != 1 else "1 vertex (0)"
            raise FormatError(
                f"face {face} uses vertex {int(mesh.corners[corner])}, but the file has {has}; nothing was written"
            )


def surface(mesh):
    """(corners, sizes, corner mask) of the faces with at least three corners."""
    keep = mesh.sizes >= 3
    mask = np.repeat(keep, mesh.sizes)
    return mesh.corners[mask], mesh.sizes[keep], mask


def starts_of(sizes):
    return np.cumsum(sizes) - sizes


def moved_rows(mesh, result):
    """The vertices whose smoothed position differs from the stored one (in the result's precision)."""
    return np.any(result != mesh.positions.astype(result.dtype), axis=1)


HOLDS_VERTEX_VALUES = (".ply",)  # the formats that can take ``added`` vertex values


def _check_added(added, ext):
    if added and ext not in HOLDS_VERTEX_VALUES:
        raise FormatError(f"a {ext[1:].upper()} file cannot hold vertex values ({', '.join(added)}): write PLY")


def updated(mesh, result, added=None):
    """The bytes of ``mesh``'s file with positions ``result`` ((n, 3) float32 or float64): moved vertices
    rewritten, the normals their faces touch recomputed, ``added`` vertex values written in (PLY only),
    everything else as it was."""
    _check_added(added, mesh.ext)
    moved = moved_rows(mesh, result)
    rows = np.flatnonzero(moved)
    corners, sizes, mask = surface(mesh)
    starts = starts_of(sizes)
    if isinstance(mesh, StlFile):
        facet_rows = np.flatnonzero(moved[mesh.corners].reshape(-1, 3).any(axis=1))
        triangles = result[mesh.corners].reshape(-1, 3, 3)[facet_rows]
        flat = np.arange(3 * len(facet_rows))
        unit = normal_maths.face_normals(
            triangles.reshape(-1, 3).astype(np.float64), flat, flat[::3], np.full(len(facet_rows), 3)
        )
        return mesh.write(triangles.astype(np.float32), unit.astype(np.float32), facet_rows)
    if isinstance(mesh, PlyFile):
        updates = {axis: (rows, result[rows, i]) for i, axis in enumerate("xyz")}
        if mesh.has_normals and len(sizes):
            new, rows_n = _normals(result, corners, starts, sizes, corners, len(result), moved)
            updates.update({axis: (rows_n, new[rows_n, i]) for i, axis in enumerate(("nx", "ny", "nz"))})
        return mesh.write(updates, added)
    updates = {"v": (rows, result[rows])}
    if mesh.has_normals and len(sizes):
        targets = mesh.corner_normals[mask]
        new, rows_n = _normals(result, corners, starts, sizes, targets, len(mesh.normals), moved)
        updates["vn"] = (rows_n, new[rows_n].astype(np.float32))
    return mesh.write(updates)


def _normals(result, corners, starts, sizes, targets, count, moved):
    """(new normals, rows to rewrite): those a moved vertex touches and that have a surface to follow."""
    new, used = normal_maths.stored_normals(result, corners, starts, sizes, targets, count)
    touched = normal_maths.touched(moved, corners, starts, sizes, targets, count)
    return new.astype(np.float32), np.flatnonzero(used & touched)


def vertex_normals(mesh, result):
    """Normals per vertex for a converted file: the smoothed surface's, a point cloud's own, or None."""
    corners, sizes, _ = surface(mesh)
    if len(sizes) and mesh.has_normals and not isinstance(mesh, StlFile):
        new, used = normal_maths.stored_normals(result, corners, starts_of(sizes), sizes, corners, len(result))
        return new.astype(np.float32)
    if not len(sizes) and isinstance(mesh, PlyFile) and mesh.has_normals:
        return mesh.normals.astype(np.float32)
    return None


def converted(mesh, result, ext, added=None):
    """The smoothed geometry of ``mesh`` as a new file in format ``ext``: positions, faces, vertex normals
    when the input has them, and ``added`` vertex values (PLY only; binary PLY and STL, as Blender's
    exporters write them). Positions keep the precision of ``result``: float64 ones become PLY ``double``
    properties or OBJ numbers that read back exactly; STL holds single precision only, and refuses float64
    positions that rounding to it would move visibly (``check_single``)."""
    _check_added(added, ext)
    positions = np.asarray(result)
    if positions.dtype != np.float64:
        positions = positions.astype(np.float32)
    corners, sizes, _ = surface(mesh)
    normals = vertex_normals(mesh, result)
    if ext == ".ply":
        return _ply_bytes(positions, corners, sizes, normals, added)
    if ext == ".obj":
        return _obj_bytes(positions, corners, sizes, normals)
    if not len(sizes):
        raise FormatError("no faces: an STL file holds triangles only")
    check_single(positions)
    return _stl_bytes(positions.astype(np.float32), corners, sizes)


# The largest move, as a share of the bounding-box diagonal, that rounding positions to single precision
# may cause in a converted STL: a hundredth of the lightest scan noise smoothed (0.1 % of the diagonal).
SINGLE_ROUNDING = 1e-5


def check_single(positions):
    """Refuse positions that single precision would move by more than SINGLE_ROUNDING of the mesh's size:
    a mesh far from the origin for its size (georeferenced scans)."""
    if positions.dtype != np.float64 or not len(positions):
        return
    moved = float(np.abs(positions.astype(np.float32) - positions).max())
    size = float(np.linalg.norm(np.ptp(positions, axis=0)))
    if moved > SINGLE_ROUNDING * size:
        far = float(np.abs(positions).max())
        raise FormatError(
            f"an STL file holds single-precision coordinates, which would move these vertices by up to {moved:.3g} "
            f"(they lie up to {far:.6g} from the origin, the mesh is {size:.3g} across): write PLY or OBJ instead"
        )


def _ply_bytes(positions, corners, sizes, normals, added=None):
    added = added or {}
    names = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else []) + list(added)
    header = [
        "ply",
        "format binary_little_endian 1.0",
        "comment written by HC Smooth",
        f"element vertex {len(positions)}",
    ]
    # x, y, z in the positions' precision (double for float64), the other values as float.
    types = {
        name: ("double", "<f8") if positions.dtype == np.float64 and name in ("x", "y", "z") else ("float", "<f4")
        for name in names
    }
    header += [f"property {types[name][0]} {name}" for name in names]
    if len(sizes):
        header += [f"element face {len(sizes)}", "property list uchar int vertex_indices"]
    header.append("end_header\n")
    columns = [positions[:, i] for i in range(3)]
    columns += [] if normals is None else [normals[:, i] for i in range(3)]
    columns += list(added.values())
    records = np.empty(len(positions), dtype=[(name, types[name][1]) for name in names])
    for name, values in zip(names, columns):
        records[name] = values
    body = records.tobytes()
    if len(sizes):
        if sizes.max() > 255:
            raise FormatError("a face with more than 255 corners cannot be written to PLY")
        lengths = 1 + 4 * sizes  # a uchar count, then int indices
        heads = np.cumsum(lengths) - lengths
        faces = np.empty(int(lengths.sum()), dtype=np.uint8)
        faces[heads] = sizes
        at = np.repeat(heads + 1, sizes) + 4 * (np.arange(len(corners)) - np.repeat(starts_of(sizes), sizes))
        faces[at[:, None] + np.arange(4)] = corners.astype("<i4").view(np.uint8).reshape(-1, 4)
        body += faces.tobytes()
    return "\n".join(header).encode() + body


def _obj_bytes(positions, corners, sizes, normals):
    lines = [b"# written by HC Smooth"]
    texts = number_texts(positions.ravel(), positions.dtype)  # float64: digits that read back exactly
    lines += [b"v %s %s %s" % row for row in zip(texts[0::3], texts[1::3], texts[2::3])]
    if normals is not None:
        lines += [b"vn %s %s %s" % tuple(row) for row in normals.astype(bytes).tolist()]
    numbers = (corners + 1).astype(bytes)
    if normals is not None:
        numbers = np.char.add(np.char.add(numbers, b"//"), numbers)
    text = numbers.tolist()
    bounds = np.cumsum(sizes).tolist()
    lines += [b"f " + b" ".join(text[a:b]) for a, b in zip([0, *bounds[:-1]], bounds)]
    return b"\n".join(lines) + b"\n"


def _stl_bytes(positions, corners, sizes):
    triangles = core.fan_triangles((np.append(starts_of(sizes), len(corners)), corners))
    records = np.zeros(len(triangles), dtype=RECORD)
    records["corners"] = positions[triangles]
    flat = np.arange(3 * len(triangles))
    records["normal"] = normal_maths.face_normals(
        positions[triangles].reshape(-1, 3).astype(np.float64), flat, flat[::3], np.full(len(triangles), 3)
    )
    header = b"binary STL written by HC Smooth".ljust(80, b" ")
    return header + np.uint32(len(triangles)).astype("<u4").tobytes() + records.tobytes()
