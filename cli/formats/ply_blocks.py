"""A binary PLY file read in blocks of records, never whole: the tiled route for scans larger than memory.

The header is parsed by ply.py's parser. The elements before the faces must have records of one size
(no list properties), and the faces one list of a fixed length (``property list uchar int
vertex_indices`` with three corners each, as scanners write triangles) beside fixed-size properties, so
that every record lies at a known offset: vertex and face records are read as NumPy structured arrays
from those offsets (``vertices``, ``faces``) and the vertex positions written back into a copy of the
file in place (``write_positions``), every other byte as it was. Face lengths that differ are found
by the pass that reads them (``faces`` checks each block) and refused with a message.
"""

import os
import shutil

import numpy as np

from .ply import FACE_LISTS, FORMATS, NORMALS, parse_header
from .tokens import FormatError

_HEADER_READ = 1 << 16  # bytes read at a time while looking for end_header


def read_header(path):
    """(header bytes, including the line after end_header), read in pieces until end_header is found."""
    data = b""
    with open(path, "rb") as file:
        while True:
            piece = file.read(_HEADER_READ)
            data += piece
            if b"end_header" in data[-len(piece) - 16 :] or not piece:
                try:
                    parse_header(data)
                    return data
                except FormatError:
                    if not piece:
                        raise
            if len(data) > 1 << 24:
                raise FormatError("PLY header longer than 16 MB (or no end_header line)")


def _dtype(element, order, what):
    """The structured dtype of ``element``'s records (fixed-size properties only)."""
    fields = []
    for prop in element.properties:
        if prop.count_type is not None:
            raise FormatError(f"its {element.name} records hold a list ({prop.name}): {what}")
        fields.append((prop.name, order + prop.type))
    names = [name for name, _ in fields]
    if len(set(names)) != len(names):
        raise FormatError(f"PLY {element.name} has two properties of one name: {what}")
    return np.dtype(fields)


class PlyBlocks:
    """A binary PLY file's header and where its vertex and face records lie (see the module docstring).

    ``vertex_count``, ``face_count``; ``precision`` the dtype positions are smoothed in (float64 where
    the file holds a double coordinate); ``has_normals`` (nx, ny, nz floats, recomputed on writing)."""

    def __init__(self, path, what="the tiled route reads records of one size"):
        self.path = path
        header = read_header(path)
        self.format, elements, body = parse_header(header)
        if self.format == "ascii":
            raise FormatError(f"an ASCII PLY file: {what} (tiles read binary PLY or OBJ; save the scan as binary PLY)")
        order = FORMATS[self.format]
        names = [element.name for element in elements]
        if "vertex" not in names:
            raise FormatError("PLY file without vertex positions (element vertex with x, y, z)")
        faces = [e for e in elements if e.name == "face" and any(e.property(n) for n in FACE_LISTS)]
        if not faces:
            raise FormatError("a PLY file without faces: point clouds are smoothed whole (--points)")
        self.face_element = faces[0]
        offset = body
        size = os.path.getsize(path)
        self.vertex_offset = self.face_offset = None
        for element in elements:
            if element is self.face_element:
                self.face_offset = offset
                self.face_dtype = self._face_dtype(element, order, offset, size, what)
                offset += element.count * self.face_dtype.itemsize
                break
            dtype = _dtype(element, order, what)
            if element.name == "vertex" and self.vertex_offset is None:
                self.vertex_offset, self.vertex_dtype, vertex = offset, dtype, element
            offset += element.count * dtype.itemsize
        if self.vertex_offset is None:
            raise FormatError(f"the PLY faces come before the vertices: {what}")
        if offset > size:
            raise FormatError(
                f"PLY file ends inside its records: they need {offset} bytes, the file has {size} (cut short, or a "
                "wrong count in the header)"
            )
        for axis in "xyz":
            prop = vertex.property(axis)
            if prop is None:
                raise FormatError("PLY file without vertex positions (element vertex with x, y, z)")
            if prop.type[0] != "f":
                raise FormatError(
                    f"PLY vertex property {axis} is not a float or double: it cannot take smoothed values"
                )
        self.vertex_count, self.face_count = vertex.count, self.face_element.count
        self.precision = np.float64 if any(vertex.property(a).type == "f8" for a in "xyz") else np.float32
        props = [vertex.property(n) for n in NORMALS]
        self.has_normals = all(p is not None and p.type[0] == "f" for p in props)

    def _face_dtype(self, element, order, offset, size, what):
        """The faces' record dtype, its list's length read from the first record (checked on every block)."""
        fields, self.corner_field = [], None
        count = 0
        for prop in element.properties:
            if prop.count_type is None:
                fields.append((prop.name, order + prop.type))
                continue
            if self.corner_field is not None or prop.name not in FACE_LISTS:
                raise FormatError(f"the PLY faces hold a list besides their corners ({prop.name}): {what}")
            if prop.type[0] not in "iu" or prop.count_type[0] not in "iu":
                raise FormatError(f"the PLY face corners are not integers ({prop.name}): {what}")
            if element.count:
                at = offset + sum(np.dtype(t).itemsize for _, t in fields)
                with open(self.path, "rb") as file:
                    file.seek(at)
                    raw = file.read(np.dtype(prop.count_type).itemsize)
                if len(raw) < np.dtype(prop.count_type).itemsize:
                    raise FormatError("PLY file ends inside its face records")
                count = int(np.frombuffer(raw, dtype=order + prop.count_type)[0])
            if count < 3:
                raise FormatError(f"the first PLY face has {count} corners: {what} (triangles or other polygons)")
            self.corner_field, self.count_field = prop.name, "__corner_count"
            fields.append((self.count_field, order + prop.count_type))
            fields.append((prop.name, order + prop.type, (count,)))
        self.corner_count = count
        return np.dtype(fields)

    # --- reading -----------------------------------------------------------------------------------

    def vertices(self, start, stop):
        """Vertex records start:stop (a structured array)."""
        return np.fromfile(
            self.path,
            dtype=self.vertex_dtype,
            count=stop - start,
            offset=self.vertex_offset + start * self.vertex_dtype.itemsize,
        )

    def positions(self, start, stop):
        """(stop - start, 3) positions of vertices start:stop in ``precision``."""
        return positions_of(self.vertices(start, stop), self.precision)

    def faces(self, start, stop):
        """(stop - start, corners) corner indices (int32; int64 from 2**31 vertices) of faces start:stop; raises
        FormatError where a face's list length differs from the first's, or a corner names a vertex the file does
        not have."""
        records = np.fromfile(
            self.path,
            dtype=self.face_dtype,
            count=stop - start,
            offset=self.face_offset + start * self.face_dtype.itemsize,
        )
        if len(records) < stop - start:
            raise FormatError("PLY file ends inside its face records")
        lengths = records[self.count_field]
        if np.any(lengths != self.corner_count):
            bad = int(np.flatnonzero(lengths != self.corner_count)[0])
            raise FormatError(
                f"PLY face {start + bad} has {lengths[bad]} corners where the first has {self.corner_count}: faces of "
                "different sizes cannot be read in tiles (triangulate the scan, or raise --memory-limit to smooth it "
                "whole)"
            )
        items = records.dtype[self.corner_field].base
        wide = self.vertex_count >= 1 << 31 or (items.kind == "u" and items.itemsize >= 4)
        corners = records[self.corner_field].astype(np.int64 if wide else np.int32)
        low, high = corners.min(initial=0), corners.max(initial=0)
        if low < 0 or high >= self.vertex_count:
            outside = (corners < 0) | (corners >= self.vertex_count)
            row = int(np.flatnonzero(outside.any(axis=1))[0])
            corner = int(corners[row][outside[row]][0])
            raise FormatError(
                f"face {start + row} uses vertex {corner}, but the file has {self.vertex_count} vertices; nothing was "
                "written"
            )
        return corners

    @property
    def normals_per_vertex(self):
        """Whether each tile writes its vertices' normals (the halo reaching one ring further)."""
        return self.has_normals

    def coordinates(self):
        """The x, y and z columns of the vertex records, as strided views of a memory map."""
        records = self.memmap_vertices()
        return [records[axis] for axis in "xyz"]

    def output(self, target):
        """Where the tiles write their results: ``target``, a copy of this file written into (``PlyOutput``)."""
        return PlyOutput(self, target)

    def memmap_vertices(self, mode="r", path=None):
        """The vertex records as a memory map (of ``path``, a copy of this file, if given)."""
        return np.memmap(
            path or self.path, dtype=self.vertex_dtype, mode=mode, offset=self.vertex_offset, shape=(self.vertex_count,)
        )


class PlyOutput:
    """A copy of the file at ``target`` whose vertex records the tiles write into in place; each write
    maps the file for itself, so that only a tile's pages stay resident (and none once it is done)."""

    def __init__(self, ply, target):
        self.ply, self.target = ply, target
        shutil.copyfile(ply.path, target)

    def _write(self, rows, values, names):
        records = self.ply.memmap_vertices("r+", self.target)
        write_columns(records, rows, values, names)
        records.flush()
        del records  # the map closed: the file can be moved or removed (on Windows too)

    def write_positions(self, rows, values):
        self._write(rows, values, "xyz")

    def write_normals(self, rows, values):
        self._write(rows, values.astype(np.float32), NORMALS)

    def finish(self):
        """Nothing left to write: the records are in place."""


def positions_of(records, precision):
    """(m, 3) positions of vertex ``records`` in ``precision``."""
    out = np.empty((len(records), 3), dtype=precision)
    for axis, name in enumerate("xyz"):
        out[:, axis] = records[name]
    return out


def write_columns(records, rows, values, names):
    """Write (m, k) ``values`` of vertex ``rows`` into the properties ``names`` of vertex ``records`` (a writable
    memory map), each value in its property's own type; nothing else changes."""
    for column, name in enumerate(names):
        records[name][rows] = values[:, column]
