"""STL (ASCII and binary) read into a mesh and written back with only the vertex coordinates and the
facet normals changed: a binary file's 80-byte header and each facet's attribute bytes (colours) as
they were, an ASCII file's text as it was except the rewritten numbers.

STL stores each facet's three corners by value: corners at exactly the same position are one vertex
of the mesh (``corners`` maps each corner to it), and each corner is written back from its vertex.
"""

import numpy as np

from .tokens import FormatError, Tokens, number_texts, splice

RECORD = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def is_binary(data):
    """A binary STL is 84 bytes plus 50 per facet (its 80-byte header may itself start with `solid`)."""
    if len(data) >= 84 and len(data) == 84 + 50 * int(np.frombuffer(data, "<u4", 1, 80)[0]):
        return True
    return not data[:1024].lstrip().lower().startswith(b"solid")


class StlFile:
    """An STL file: ``positions`` (n, 3) float64 of the merged vertices, triangles as ``corners``."""

    ext = ".stl"
    has_normals = True  # facet normals: always there, recomputed from the smoothed facet
    precision = np.float32  # what STL stores, ASCII ones included (their numbers come from floats)

    def __init__(self, data):
        self.data = data
        self.binary = is_binary(data)
        if self.binary:
            if len(data) < 84 or len(data) != 84 + 50 * int(np.frombuffer(data, "<u4", 1, 80)[0]):
                raise FormatError("binary STL whose size does not match its facet count")
            self.records = np.frombuffer(data, RECORD, offset=84)
            corners = self.records["corners"].reshape(-1, 3).astype(np.float64)
        else:
            self.tokens = tokens = Tokens(data)
            index = np.arange(len(tokens))
            self.vertex = index[tokens.is_word(index, b"vertex")]
            facet = index[tokens.is_word(index, b"facet")]
            self.normal = facet + 1
            if self.normal.size and (
                self.normal[-1] + 3 >= len(tokens) or not tokens.is_word(self.normal, b"normal").all()
            ):
                raise FormatError("ASCII STL: 'facet' without 'normal'")
            if len(self.vertex) != 3 * len(facet) or (
                len(facet)
                and not np.array_equal(np.searchsorted(facet, self.vertex), np.repeat(np.arange(1, len(facet) + 1), 3))
            ):
                raise FormatError("ASCII STL: every facet needs exactly three vertices")
            if self.vertex.size and self.vertex[-1] + 3 >= len(tokens):
                raise FormatError("ASCII STL ends inside a vertex")
            corners = tokens.numbers(self.vertex[:, None] + np.arange(1, 4), "STL vertex")
        if not np.isfinite(corners).all():
            self.positions = corners  # refused by the caller with the others
            self.corners = np.arange(len(corners))
        else:
            self.positions, self.corners = _merge(corners)
        self.sizes = np.full(len(corners) // 3, 3, dtype=np.int64)

    def write(self, corners, facet_normals, rows):
        """The file's bytes with ``corners`` ((facets, 3, 3) float32) and ``facet_normals`` written to the
        facets ``rows``."""
        if self.binary:
            records = self.records.copy()
            records["corners"][rows] = corners
            records["normal"][rows] = facet_normals
            return self.data[:84] + records.tobytes()
        tokens = self.tokens
        corner_tokens = self.vertex.reshape(-1, 3)[rows][:, :, None] + np.arange(1, 4)
        normal_tokens = self.normal[rows][:, None] + np.arange(1, 4)
        where = np.concatenate([corner_tokens.ravel(), normal_tokens.ravel()])
        texts = number_texts(np.concatenate([corners.ravel(), facet_normals.ravel()]), np.float32)
        return splice(self.data, tokens.starts[where], tokens.ends[where], texts)


def _merge(corners):
    """(positions, index of each corner's position): corners at exactly one position (0.0 and -0.0 alike)
    are one vertex, numbered in the order they first appear."""
    exact = np.ascontiguousarray(corners + 0.0)  # -0.0 + 0.0 is 0.0
    keys = exact.view(np.dtype((np.void, exact.dtype.itemsize * 3))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return corners[first[order]], rank[inverse.ravel()].astype(np.int64)
