"""A Wavefront OBJ file read in blocks, never whole: the tiled route for scans larger than memory.

Text has no records at known offsets, so one pass over the file (in pieces of whole lines, parsed as
obj.py parses a whole file) indexes it into scratch files beside the output: the `v` positions (float64,
24 bytes a vertex) and the faces' corners and `vn` indices (int64, 0-based: OBJ's 1-based and negative,
relative indices resolved as obj.py resolves them). The tiles read blocks of those as they read a binary
PLY's records (``positions``, ``faces``; the faces must all have one corner count, as in PLY) and write
their vertices' results into a scratch copy of the positions (``ObjOutput``). Then the `vn` normals are
summed over all faces from the result (the sums in the faces' order, as obj.py's whole run adds them), and
a last pass copies the file into the output with only the numbers of the moved `v` lines and the touched
`vn` lines replaced, written as the whole run writes them: every other byte stays.
"""

import contextlib
import os
import shutil

import numpy as np

from ... import core
from . import normals as normal_maths
from .obj import _absolute, check_continuations, corner_tokens, elements, face_numbers, rewritten, statements
from .tokens import FormatError, Tokens

CHUNK = 1 << 21  # bytes of text parsed at a time (whole lines): its tokens and texts take about 30 times that
BLOCK = 1 << 17  # faces per block of the `vn` pass (its corner vectors take about 400 bytes a face)
_UNCHECKED = np.iinfo(np.int64).max  # the vertices a face may name before the pass has counted them all


def pieces(path):
    """The file's text in pieces of about CHUNK bytes, each ending at a line's end (the last at the file's)."""
    size = CHUNK
    with open(path, "rb") as file:
        rest = b""
        while True:
            piece = file.read(size)
            data = rest + piece
            if not piece:
                if data:
                    yield data
                return
            cut = data.rfind(b"\n") + 1
            rest = data[cut:]
            if cut:
                yield data[:cut]


def blocks(count):
    return ((start, min(start + BLOCK, count)) for start in range(0, count, BLOCK))


class ObjBlocks:
    """An OBJ file indexed into scratch files (see the module docstring); a context manager that removes them.

    ``vertex_count``, ``face_count``, ``corner_count`` (of every face), ``normal_count`` (`vn` lines);
    ``scratch()`` names a new scratch file (beside the output)."""

    precision = np.float64
    normals_per_vertex = False  # the `vn` are recomputed once every tile is done (ObjOutput.finish)

    def __init__(self, path, scratch):
        self.path, self._scratch, self._made = path, scratch, []
        self.vertex_count = self.face_count = self.normal_count = 0
        self.corner_count = None
        try:
            self._index()
        except BaseException:
            self.close()
            raise

    def __enter__(self):
        return self

    def __getstate__(self):
        """A copy for a worker (cli/tiled.py's TileJob): it reads the scratch files; this one removes them."""
        return {**self.__dict__, "_scratch": None, "_made": []}

    def __exit__(self, *exc):
        self.close()

    def close(self):
        for path in self._made:
            with contextlib.suppress(OSError):
                os.remove(path)
        self._made = []

    def scratch(self):
        path = self._scratch()
        self._made.append(path)
        return path

    def _index(self):
        self.position_path, self.corner_path, self.normal_path = self.scratch(), self.scratch(), self.scratch()
        line = 0
        highest = np.array([-1, -1])  # the largest vertex and vn index a face names
        with (
            open(self.position_path, "wb") as positions,
            open(self.corner_path, "wb") as corners,
            open(self.normal_path, "wb") as normals,
        ):
            for data in pieces(self.path):
                check_continuations(data)
                tokens = Tokens(data)
                statement, arguments = statements(tokens)
                v, vn, f, sizes = elements(tokens, statement, arguments, line)
                positions.write(tokens.numbers(v[:, None] + np.arange(1, 4), "OBJ vertex").tobytes())
                if len(f):
                    self._check_sizes(sizes, tokens.lines[f] + line)
                    vertices, used = self._corners(tokens, v, vn, f, sizes)
                    corners.write(vertices.tobytes())
                    normals.write(used.tobytes())
                    highest = np.maximum(highest, [vertices.max(), used.max()])
                self.vertex_count += len(v)
                self.normal_count += len(vn)
                self.face_count += len(f)
                line += data.count(b"\n")
        for index, count, what in zip(
            highest.tolist(), (self.vertex_count, self.normal_count), ("vertex", "normal (vn)")
        ):
            if index >= count:
                raise FormatError(f"OBJ face: {what} index {index + 1} is out of range (the file has {count} in all)")
        if not self.face_count:
            raise FormatError("an OBJ file without faces: point clouds are smoothed whole (--points)")

    def _check_sizes(self, sizes, lines):
        """Refuse faces whose corner count differs from the first face's (their blocks would not be of one size)."""
        if self.corner_count is None:
            self.corner_count = int(sizes[0])
            if self.corner_count < 3:
                raise FormatError(
                    f"the first OBJ face (line {lines[0] + 1}) has {self.corner_count} corners: faces of fewer than "
                    "three corners cannot be read in tiles (raise --memory-limit to smooth it whole)"
                )
        other = np.flatnonzero(sizes != self.corner_count)
        if other.size:
            at = int(other[0])
            raise FormatError(
                f"OBJ face {self.face_count + at} (line {lines[at] + 1}) has {sizes[at]} corners where the first has "
                f"{self.corner_count}: faces of different sizes cannot be read in tiles (triangulate the scan, or "
                "raise --memory-limit to smooth it whole)"
            )

    def _corners(self, tokens, v, vn, f, sizes):
        """(vertex, vn) index of each corner of faces ``f`` of a piece, counted over the whole file (vn -1: none);
        indices past the vertices counted so far are checked once the pass has counted them all."""
        values, first, per_corner = face_numbers(tokens, corner_tokens(f, sizes))
        line_of = np.repeat(tokens.lines[f], sizes)
        before = np.searchsorted(tokens.lines[v], line_of) + self.vertex_count
        vertices = _absolute(values[first], before, _UNCHECKED, "vertex")
        normals = np.full(len(vertices), -1, dtype=np.int64)
        with_normal = per_corner == 2
        if with_normal.any():
            before = np.searchsorted(tokens.lines[vn], line_of[with_normal]) + self.normal_count
            normals[with_normal] = _absolute(values[first[with_normal] + 2], before, _UNCHECKED, "normal (vn)")
        return vertices, normals

    # --- reading -----------------------------------------------------------------------------------

    def positions(self, start, stop, path=None):
        """(stop - start, 3) float64 positions of vertices start:stop (of the result copy at ``path`` if given)."""
        values = np.fromfile(path or self.position_path, dtype=np.float64, count=3 * (stop - start), offset=24 * start)
        return values.reshape(-1, 3)

    def faces(self, start, stop, path=None):
        """(stop - start, corners) int64 vertex indices of faces start:stop (their vn indices from ``path``)."""
        k = self.corner_count
        values = np.fromfile(path or self.corner_path, dtype=np.int64, count=k * (stop - start), offset=8 * k * start)
        return values.reshape(-1, k)

    def coordinates(self):
        """The x, y and z columns of the positions, as views of a memory map."""
        positions = np.memmap(self.position_path, dtype=np.float64, mode="r", shape=(self.vertex_count, 3))
        return [positions[:, axis] for axis in range(3)]

    def output(self, target):
        """Where the tiles write their results (``ObjOutput``); its ``finish`` writes ``target``."""
        return ObjOutput(self, target)


class ObjOutput:
    """The tiles' results, in a scratch copy of the positions; ``finish`` writes the output file."""

    def __init__(self, obj, target):
        self.obj, self.target = obj, target
        self.path = obj.scratch()
        shutil.copyfile(obj.position_path, self.path)

    def _map(self, count, mode="r+"):
        return np.memmap(self.path, dtype=np.float64, mode=mode, shape=(count, 3))

    def write_positions(self, rows, values):
        """Vertex ``rows`` take ``values`` (a map opened for one tile: only its pages stay resident)."""
        result = self._map(self.obj.vertex_count)
        result[rows] = values
        result.flush()
        del result

    def finish(self):
        """Write the output file: the input with the moved `v` and the touched `vn` rewritten."""
        obj = self.obj
        normals = self._normals() if obj.normal_count else None
        v_at = vn_at = 0
        with open(self.target, "wb") as out:
            for data in pieces(obj.path):
                tokens = Tokens(data)
                statement, arguments = statements(tokens)
                v, vn, _, _ = elements(tokens, statement, arguments)
                updates = []
                if len(v):
                    before = obj.positions(v_at, v_at + len(v))
                    after = obj.positions(v_at, v_at + len(v), self.path)
                    rows = np.flatnonzero(np.any(after != before, axis=1))
                    updates.append((v, rows, after[rows]))
                if len(vn) and normals is not None:
                    new, rewrite = normals.rows(vn_at, vn_at + len(vn))
                    rows = np.flatnonzero(rewrite)
                    updates.append((vn, rows, new[rows]))
                out.write(rewritten(data, tokens, updates))
                v_at, vn_at = v_at + len(v), vn_at + len(vn)

    def _normals(self):
        """The `vn` normals of the result (cli/formats/normals.py's rule): each the angle-weighted sum of the
        face normals of the corners that name it, added corner after corner in the faces' order."""
        obj = self.obj
        sums = StoredNormals(obj)
        k = obj.corner_count
        for start, stop in blocks(obj.face_count):
            corners = obj.faces(start, stop)
            targets = obj.faces(start, stop, obj.normal_path).ravel()
            vertices, local = np.unique(corners, return_inverse=True)
            after, before = (
                self._map(obj.vertex_count, "r"),
                np.memmap(obj.position_path, dtype=np.float64, mode="r", shape=(obj.vertex_count, 3)),
            )
            points = np.asarray(after[vertices])
            moved = np.any(points != before[vertices], axis=1)
            del after, before
            sizes = np.full(len(corners), k)
            vectors = normal_maths.corner_vectors(points, local.ravel(), np.arange(len(corners)) * k, sizes)
            corner_moved = np.repeat(moved[local.reshape(-1, k)].any(axis=1), k)
            sums.add(targets, vectors, corner_moved)
        return sums


class StoredNormals:
    """Per `vn`: the sum of its corners' vectors (float64) and whether a moved vertex touches it, in scratch files."""

    def __init__(self, obj):
        self.count = obj.normal_count
        self.sum_path, self.touched_path = obj.scratch(), obj.scratch()
        for path, size in ((self.sum_path, 24 * self.count), (self.touched_path, self.count)):
            with open(path, "wb") as file:
                file.truncate(size)  # zeros

    def add(self, targets, vectors, corner_moved):
        take = targets >= 0
        sums = np.memmap(self.sum_path, dtype=np.float64, mode="r+", shape=(self.count, 3))
        for axis in range(3):  # corner after corner, as np.bincount adds them in the whole run
            np.add.at(sums[:, axis], targets[take], vectors[take, axis])
        sums.flush()
        touched = np.memmap(self.touched_path, dtype=np.uint8, mode="r+", shape=(self.count,))
        touched[targets[take & corner_moved]] = 1
        touched.flush()
        del sums, touched

    def rows(self, start, stop):
        """(float32 unit normals, which to rewrite) of `vn` start:stop: those some corner adds to, non-zero,
        and touched by a moved vertex."""
        sums = np.fromfile(self.sum_path, dtype=np.float64, count=3 * (stop - start), offset=24 * start).reshape(-1, 3)
        touched = np.fromfile(self.touched_path, dtype=np.uint8, count=stop - start, offset=start)
        used = np.linalg.norm(sums, axis=1) > 0
        return core.unit_rows(sums).astype(np.float32), used & (touched > 0)
