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
    """A binary STL is 84 bytes plus 50 per facet. Its 80-byte header may itself start with `solid`: then a
    NUL byte among the first 84 tells it from an ASCII STL, also when it is cut short (text has none; the
    facet count has one below 16 million facets)."""
    if len(data) >= 84 and len(data) == 84 + 50 * int(np.frombuffer(data, "<u4", 1, 80)[0]):
        return True
    return not data[:1024].lstrip().lower().startswith(b"solid") or b"\0" in data[:84]


class StlFile:
    """An STL file: ``positions`` (n, 3) float64 of the merged vertices, triangles as ``corners``."""

    ext = ".stl"
    has_normals = True  # facet normals: always there, recomputed from the smoothed facet
    precision = np.float32  # what STL stores, ASCII ones included (their numbers come from floats)

    def __init__(self, data):
        self.data = data
        self.binary = is_binary(data)
        if self.binary:
            if len(data) < 84:
                raise FormatError(f"binary STL cut short: {len(data)} bytes, less than its 84-byte header")
            count = int(np.frombuffer(data, "<u4", 1, 80)[0])
            if len(data) != 84 + 50 * count:
                raise FormatError(
                    f"binary STL cut short or invalid: its header counts {count} facets (84 + 50 x {count} = "
                    f"{84 + 50 * count} bytes), and the file has {len(data)} bytes"
                )
            self.records = np.frombuffer(data, RECORD, offset=84)
            with np.errstate(invalid="ignore"):  # a signalling NaN: refused with the others by formats.check
                corners = self.records["corners"].reshape(-1, 3).astype(np.float64)
        else:
            self.tokens = tokens = Tokens(data)
            facet = _facets(tokens)
            self.normal = facet + 1
            self.vertex = (facet[:, None] + VERTICES).ravel()
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


# An ASCII facet, token by token: `facet normal x y z`, `outer loop`, three `vertex x y z`, `endloop`, `endfacet`.
FACET_WORDS = (
    (0, b"facet"),
    (1, b"normal"),
    (5, b"outer"),
    (6, b"loop"),
    (7, b"vertex"),
    (11, b"vertex"),
    (15, b"vertex"),
    (19, b"endloop"),
    (20, b"endfacet"),
)
VERTICES = np.array([offset for offset, word in FACET_WORDS if word == b"vertex"])
FACET_TOKENS = 21


def _facets(tokens):
    """The index of each facet's `facet` token; raises FormatError for a facet out of the layout above,
    a vertex outside a facet, or a file that ends before `endsolid` follows its last facet."""
    index = np.arange(len(tokens))
    facet = index[tokens.is_word(index, b"facet")]
    if len(facet) and facet[-1] + FACET_TOKENS > len(tokens):
        raise FormatError(f"ASCII STL ends inside facet {len(facet) - 1} (the file is cut short)")
    for offset, word in FACET_WORDS:
        wrong = np.flatnonzero(~tokens.is_word(facet + offset, word))
        if wrong.size:
            found = tokens.text(facet[wrong[:1]] + offset).strip().decode("ascii", "replace")
            raise FormatError(f"ASCII STL facet {wrong[0]}: '{found}' where '{word.decode()}' belongs")
    if np.count_nonzero(tokens.is_word(index, b"vertex")) != len(VERTICES) * len(facet):
        raise FormatError("ASCII STL: every facet needs exactly three vertices")
    after = index[facet[-1] + FACET_TOKENS :] if len(facet) else index
    if not tokens.is_word(after, b"endsolid").any():
        raise FormatError("ASCII STL ends early: no 'endsolid' after its last facet (the file is cut short)")
    return facet


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
