"""Wavefront OBJ read into arrays and written back with only the `v` positions (and the `vn` normals,
where the file has them) changed: every other line, and every other token of a changed line, as it
was. The material library (`mtllib`) and the textures it names are never read or written.
"""

import numpy as np

from .tokens import FormatError, Tokens, integers, number_texts, parse_numbers, splice


class ObjFile:
    """An OBJ file: ``positions`` (n, 3) float64, faces as ``corners`` with ``sizes``, and for each
    corner its `vn` index in ``corner_normals`` (-1: none)."""

    ext = ".obj"
    precision = np.float64  # text: as many digits as the writer gave (georeferenced scans need doubles)

    def __init__(self, data):
        check_continuations(data)
        self.data = data
        self.tokens = tokens = Tokens(data)
        statement, arguments = statements(tokens)
        self.v, self.vn, f, self.sizes = elements(tokens, statement, arguments)
        self.positions = tokens.numbers(self.v[:, None] + np.arange(1, 4), "OBJ vertex")
        self.has_normals = len(self.vn) > 0
        self.normals = tokens.numbers(self.vn[:, None] + np.arange(1, 4), "OBJ vn") if self.has_normals else None
        self._faces(f)
        self._f = f
        g = statement[tokens.is_word(statement, b"g")]
        self._g = g, arguments[np.searchsorted(statement, g)]

    def _faces(self, f):
        tokens = self.tokens
        corner = corner_tokens(f, self.sizes)
        if corner.size == 0:
            self.corners = np.zeros(0, np.int64)
            self.corner_normals = np.zeros(0, np.int64)
            return
        values, first, per_corner = face_numbers(tokens, corner)
        line_of = np.repeat(tokens.lines[f], self.sizes)
        # Negative indices count back from the last v (vn) before the face's line.
        vertices = _absolute(values[first], np.searchsorted(tokens.lines[self.v], line_of), len(self.v), "vertex")
        normals = np.full(len(vertices), -1, dtype=np.int64)
        with_normal = per_corner == 2
        if with_normal.any():
            given = values[first[with_normal] + 2]
            before = np.searchsorted(tokens.lines[self.vn], line_of[with_normal])
            normals[with_normal] = _absolute(given, before, len(self.vn), "normal (vn)")
        self.corners, self.corner_normals = vertices, normals

    def groups(self, names):
        """{name: vertex indices} of the OBJ groups (`g` lines) among ``names``: the vertices of the faces
        that follow a `g` line naming the group, up to the next `g` line (as Blender's importer makes
        vertex groups of them)."""
        g, counts = self._g
        tokens = self.tokens
        # Each face's group statement: the last g line before it (-1: none).
        statement = np.searchsorted(g, self._f) - 1
        corner_statement = np.repeat(statement, self.sizes)
        found = {}
        for k, (at, count) in enumerate(zip(g.tolist(), counts.tolist())):
            for token in range(at + 1, at + 1 + count):
                name = self.data[tokens.starts[token] : tokens.ends[token]].decode("utf-8", "replace")
                if name in names:
                    found.setdefault(name, []).append(k)
        return {name: np.unique(self.corners[np.isin(corner_statement, ks)]) for name, ks in found.items()}

    def write(self, updates):
        """The file's bytes with ``updates`` ({"v" or "vn": (rows, values)}) written in."""
        return rewritten(
            self.data,
            self.tokens,
            [(self.v if name == "v" else self.vn, rows, values) for name, (rows, values) in updates.items()],
        )


def rewritten(data, tokens, updates):
    """``data`` with, for each (keywords, rows, values) of ``updates``, the three numbers after the keyword
    tokens ``keywords[rows]`` replaced by ``values`` (float64 as such, anything else as float32)."""
    starts, ends, texts = [], [], []
    for keywords, rows, values in updates:
        where = keywords[rows][:, None] + np.arange(1, 4)
        starts.append(tokens.starts[where].ravel())
        ends.append(tokens.ends[where].ravel())
        texts += number_texts(np.asarray(values).ravel(), values.dtype if values.dtype == np.float64 else np.float32)
    if not starts:
        return bytes(data)
    return splice(data, np.concatenate(starts), np.concatenate(ends), texts)


def check_continuations(data):
    if b"\\\n" in data or b"\\\r\n" in data:
        raise FormatError("OBJ line continuations (a line ending in a backslash) are not supported")


def elements(tokens, statement, arguments, first_line=0):
    """(v, vn, f, sizes): the tokens of the `v`, `vn` and `f` keywords among ``statements``, and each face's
    corner count; raises FormatError for a v or vn line of fewer than three numbers (its line counted from
    ``first_line``)."""
    v = statement[tokens.is_word(statement, b"v")]
    vn = statement[tokens.is_word(statement, b"vn")]
    f = statement[tokens.is_word(statement, b"f")]
    v_args = arguments[np.searchsorted(statement, v)]
    if np.any(v_args < 3):
        raise FormatError(f"OBJ line {first_line + tokens.lines[v[v_args < 3][0]] + 1}: a vertex needs x, y and z")
    if np.any(arguments[np.searchsorted(statement, vn)] < 3):
        raise FormatError("OBJ: a vn line needs x, y and z")
    return v, vn, f, arguments[np.searchsorted(statement, f)]


def statements(tokens):
    """(statements, arguments): the first token of each line that is not a comment, and how many tokens
    follow it on its line before a comment (a token starting with # and everything after it on its line)."""
    count = len(tokens)
    lines = tokens.lines
    first = np.ones(count, dtype=bool)
    first[1:] = lines[1:] != lines[:-1]
    hashes = tokens.bytes[tokens.starts] == ord("#") if count else np.zeros(0, bool)
    line_start = np.maximum.accumulate(np.where(first, np.arange(count), 0)) if count else np.zeros(0, int)
    last_hash = np.maximum.accumulate(np.where(hashes, np.arange(count), -1)) if count else np.zeros(0, int)
    live = last_hash < line_start
    statement = np.flatnonzero(first & live)
    live_count = np.bincount(lines[live], minlength=int(lines[-1]) + 1 if count else 0)
    return statement, live_count[lines[statement]] - 1


def corner_tokens(f, sizes):
    """The tokens of the corners of the faces whose `f` tokens are ``f`` (with ``sizes`` corners each)."""
    return np.repeat(f + 1, sizes) + (np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes))


def face_numbers(tokens, corner):
    """(values, first, per_corner) of the face corner tokens ``corner`` (v, v/vt, v//vn, v/vt/vn): their
    numbers in a row (an empty vt read as 0), where each corner's first number lies, and its slashes."""
    text = tokens.text(corner)
    slashes = np.frombuffer(text, np.uint8) == ord("/")
    per_corner = np.add.reduceat(
        slashes, np.concatenate(([0], np.cumsum(tokens.ends[corner] - tokens.starts[corner] + 1)[:-1]))
    )
    values = integers(
        parse_numbers(text.replace(b"//", b"/0/").replace(b"/", b" "), int((per_corner + 1).sum()), "OBJ face"),
        "OBJ face",
    )
    first = np.cumsum(per_corner + 1) - (per_corner + 1)
    return values, first, per_corner


def _absolute(given, before, total, what):
    """OBJ's 1-based (and negative, relative) indices as 0-based; raises FormatError for one out of range."""
    index = np.where(given > 0, given - 1, before + given)
    limit = np.where(given > 0, total, before)  # a negative index counts back from the lines before its face
    bad = np.flatnonzero((given == 0) | (index < 0) | (index >= limit))
    if bad.size:
        first = bad[0]
        if given[first] == 0:
            raise FormatError(f"OBJ face: {what} index 0 (OBJ indices start at 1)")
        where = "at that point" if given[first] < 0 else "in all"
        raise FormatError(
            f"OBJ face: {what} index {int(given[first])} is out of range (the file has {int(limit[first])} {where})"
        )
    return index.astype(np.int64)
