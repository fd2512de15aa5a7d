"""PLY (ASCII, binary little and big endian) read into arrays and written back with only the vertex
positions (and the vertex normals nx, ny, nz, where the file has them and faces) changed.

Every element, property, comment and obj_info line is kept: the header as it was, binary records byte
for byte outside the rewritten values, ASCII lines as they were except the rewritten tokens. A float
vertex property can be added (the deviation map's ``hc_deviation``): one line in the header after the
vertex's last property, one value at the end of each vertex record; one the file has is rewritten.
"""

import re

import numpy as np

from .tokens import FormatError, Tokens, integers, number_texts, splice

TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
FACE_LISTS = ("vertex_indices", "vertex_index")
NORMALS = ("nx", "ny", "nz")


class Property:
    def __init__(self, words):
        if len(words) > 1 and words[1] == "list":
            if len(words) != 5 or words[2] not in TYPES or words[3] not in TYPES:
                raise FormatError(f"PLY header: bad list property '{' '.join(words)}'")
            self.count_type, self.type, self.name = TYPES[words[2]], TYPES[words[3]], words[4]
        else:
            if len(words) != 3 or words[1] not in TYPES:
                raise FormatError(f"PLY header: bad property '{' '.join(words)}'")
            self.count_type, self.type, self.name = None, TYPES[words[1]], words[2]


class Element:
    def __init__(self, name, count):
        self.name, self.count, self.properties = name, count, []
        self.where = {}  # property name -> (count,) byte offsets (binary) or token indices (ASCII)
        self.ends = None  # (count,) byte offset just past each record (binary) or its last token's index (ASCII)
        self.counts = {}  # list property name -> (count,) list lengths

    def property(self, name):
        return next((p for p in self.properties if p.name == name), None)


# The line that ends the header: end_header alone on it (a comment may hold the word).
END_HEADER = re.compile(rb"(?:\A|\n)[ \t]*end_header[ \t\r]*(?:\n|\Z)")


def header_end(data):
    """(offset of the end_header line, offset of the body after it)."""
    found = END_HEADER.search(data)
    if found is None:
        raise FormatError("PLY header without an end_header line")
    return found.start(), found.end()


def parse_header(data):
    """(format word, [Element], offset of the body)."""
    if not data.startswith(b"ply") or data[3:4] not in (b"\n", b"\r"):
        raise FormatError("not a PLY file (it does not start with 'ply')")
    end, body = header_end(data)
    fmt, elements = None, []
    for line in data[:end].decode("ascii", "replace").splitlines()[1:]:
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            if len(words) < 2 or words[1] not in FORMATS:
                raise FormatError(f"PLY header: unknown format '{line.strip()}'")
            fmt = words[1]
        elif words[0] == "element":
            if len(words) != 3 or not words[2].isdigit() or len(words[2]) > 18:
                raise FormatError(f"PLY header: bad element line '{line.strip()}' (a count of 0 to 18 digits)")
            elements.append(Element(words[1], int(words[2])))
        elif words[0] == "property":
            if not elements:
                raise FormatError("PLY header: a property before any element")
            elements[-1].properties.append(Property(words))
        else:
            raise FormatError(f"PLY header: unknown line '{line.strip()}'")
    if fmt is None:
        raise FormatError("PLY header without a format line")
    return fmt, elements, body


def check_counts(fmt, elements, available):
    """Refuse element counts that need more than the ``available`` bytes after the header, before anything
    is allocated for them: a binary record takes at least its fixed-size values and list lengths (a list
    may be empty), an ASCII value at least a byte."""
    need = 0
    for element in elements:
        if fmt == "ascii":
            least = len(element.properties)
        else:
            least = sum(np.dtype(p.type if p.count_type is None else p.count_type).itemsize for p in element.properties)
        need += element.count * least
        if need > available:
            raise FormatError(
                f"PLY file ends before its {element.count} {element.name} records: with the elements before them "
                f"they need at least {need} bytes after the header, and the file has {available} (cut short, or a "
                "wrong count in the header)"
            )


class PlyFile:
    """A PLY file: ``positions`` (n, 3) float64 and faces as ``corners`` with ``sizes`` (corners per face)."""

    ext = ".ply"

    def __init__(self, data):
        self.data = data
        self.format, self.elements, body = parse_header(data)
        vertex = next((e for e in self.elements if e.name == "vertex"), None)
        if vertex is None or not all(vertex.property(axis) for axis in "xyz"):
            raise FormatError("PLY file without vertex positions (element vertex with x, y, z)")
        for axis in "xyz":
            prop = vertex.property(axis)
            if prop.count_type is not None or prop.type[0] != "f":
                raise FormatError(
                    f"PLY vertex property {axis} is not a float or double: it cannot take smoothed values"
                )
        self.vertex = vertex
        check_counts(self.format, self.elements, len(data) - body)
        if self.format == "ascii":
            self._locate_ascii(body)
        else:
            self._locate_binary(body)
        self.positions = np.stack([self._read(vertex, axis) for axis in "xyz"], axis=1)
        # The precision the file keeps its positions in: the smoothing runs in it.
        self.precision = np.float64 if any(vertex.property(axis).type == "f8" for axis in "xyz") else np.float32
        self.face = next(
            (e for e in self.elements if e.name == "face" and any(e.property(n) for n in FACE_LISTS)), None
        )
        if self.face is not None:
            name = next(n for n in FACE_LISTS if self.face.property(n))
            corners, self.sizes = self._read_list(self.face, name)
            self.corners = integers(np.asarray(corners, dtype=np.float64), f"PLY face {name}")
        else:
            self.corners, self.sizes = np.zeros(0, np.int64), np.zeros(0, np.int64)
        props = [vertex.property(n) for n in NORMALS]
        self.has_normals = all(p is not None and p.count_type is None and p.type[0] == "f" for p in props)
        self.normals = np.stack([self._read(vertex, n) for n in NORMALS], axis=1) if self.has_normals else None

    # --- where the values are ---------------------------------------------------------------------

    def _locate_ascii(self, body):
        self.tokens = tokens = Tokens(self.data, body)
        # One record per line (as every PLY writer puts them): the records are the lines with tokens.
        lines, first = np.unique(tokens.lines, return_index=True)
        per_record = np.diff(np.append(first, len(tokens)))
        record = 0
        for element in self.elements:
            if record + element.count > len(first):
                raise FormatError(f"PLY file ends before its {element.count} {element.name} records")
            start = first[record : record + element.count]
            values = per_record[record : record + element.count]
            offset = np.zeros(element.count, dtype=np.int64)
            for prop in element.properties:
                element.where[prop.name] = start + offset
                if prop.count_type is None:
                    offset += 1
                    continue
                short = np.flatnonzero(offset >= values)  # the list's length lies past its record's line
                if short.size:
                    bad = short[0]
                    raise FormatError(
                        f"PLY {element.name} record {bad} has {values[bad]} values, fewer than the header says"
                    )
                counts = tokens.numbers(start + offset, f"PLY {element.name} {prop.name}")
                counts = integers(counts, f"PLY {element.name} {prop.name} count")
                element.counts[prop.name] = _lengths(counts, element, prop)
                offset += 1 + element.counts[prop.name]
            element.ends = start + offset - 1
            if not np.array_equal(offset, values):
                bad = int(np.flatnonzero(offset != values)[0])
                raise FormatError(
                    f"PLY {element.name} record {bad} has {values[bad]} values where the header says {offset[bad]}"
                )
            record += element.count

    def _locate_binary(self, body):
        order = FORMATS[self.format]
        raw = np.frombuffer(self.data, dtype=np.uint8)
        position = body
        for element in self.elements:
            if not element.properties:  # records of no bytes
                continue
            starts = _record_starts(raw, position, element, order)
            offset = starts.copy()
            for prop in element.properties:
                element.where[prop.name] = offset.copy()
                if prop.count_type is None:
                    offset += np.dtype(prop.type).itemsize
                else:
                    counts = _lengths(_gather(raw, offset, order + prop.count_type), element, prop)
                    element.counts[prop.name] = counts
                    offset += np.dtype(prop.count_type).itemsize + counts * np.dtype(prop.type).itemsize
            element.ends = offset
            position = int(offset[-1]) if element.count else position
            if position > len(self.data):
                raise FormatError(f"PLY file ends inside its {element.name} records")

    # --- reading and writing values ----------------------------------------------------------------

    def _read(self, element, name):
        where = element.where[name]
        if self.format == "ascii":
            return self.tokens.numbers(where, f"PLY {element.name} {name}")
        prop = element.property(name)
        raw = np.frombuffer(self.data, dtype=np.uint8)
        with np.errstate(invalid="ignore"):  # a signalling NaN: refused with the others by formats.check
            return _gather(raw, where, FORMATS[self.format] + prop.type).astype(np.float64)

    def _read_list(self, element, name):
        prop, counts, where = element.property(name), element.counts[name], element.where[name]
        total = int(counts.sum())
        first = np.repeat(np.cumsum(counts) - counts, counts)
        step = np.arange(total) - first  # item number within its list
        if self.format == "ascii":
            items = np.repeat(where + 1, counts) + step
            values = self.tokens.numbers(items, f"PLY {element.name} {name}")
        else:
            size = np.dtype(prop.type).itemsize
            items = np.repeat(where + np.dtype(prop.count_type).itemsize, counts) + step * size
            raw = np.frombuffer(self.data, dtype=np.uint8)
            values = _gather(raw, items, FORMATS[self.format] + prop.type)
        return values, counts

    def write(self, updates, added=None):
        """The file's bytes with ``updates`` ({vertex property name: (rows, values)}) written in, and ``added``
        ({name: one value per vertex}) as float vertex properties: rewritten where the file has a float or
        double of that name, else added after the vertex's last property."""
        updates, new = dict(updates), {}
        for name, values in (added or {}).items():
            prop = self.vertex.property(name)
            if prop is None:
                new[name] = np.asarray(values, dtype=np.float32)
            elif prop.count_type is None and prop.type[0] == "f":
                updates[name] = (np.arange(self.vertex.count), values)
            else:
                raise FormatError(f"PLY vertex property {name} is not a float or double: it cannot take its values")
        if self.format == "ascii":
            return self._write_ascii(updates, new)
        out = bytearray(self.data)
        raw = np.frombuffer(out, dtype=np.uint8)
        for name, (rows, values) in updates.items():
            dtype = np.dtype(FORMATS[self.format] + self.vertex.property(name).type)
            offsets = self.vertex.where[name][rows]
            raw[offsets[:, None] + np.arange(dtype.itemsize)] = (
                np.asarray(values, dtype=dtype).view(np.uint8).reshape(-1, dtype.itemsize)
            )
        if not new:
            return bytes(out)
        # Each record's new values go just past its end: the insertions at one offset keep their order.
        dtype = np.dtype(FORMATS[self.format] + "f4")
        values = np.stack([new[name] for name in new], axis=1).astype(dtype).view(np.uint8)
        at = np.repeat(self.vertex.ends, values.shape[1])
        body = np.insert(raw, at, values.ravel())
        header = self._header_with(new)
        return header + body[self._header_end() :].tobytes()

    def _write_ascii(self, updates, new):
        starts, ends, texts = [], [], []
        for name, (rows, values) in updates.items():
            where = self.vertex.where[name][rows]
            starts.append(self.tokens.starts[where])
            ends.append(self.tokens.ends[where])
            texts += number_texts(values, self.vertex.property(name).type)
        if new:
            # After each vertex record's last token: an empty span, filled with the new values.
            after = self.tokens.ends[self.vertex.ends]
            starts.append(after)
            ends.append(after)
            columns = [number_texts(values, "f4") for values in new.values()]
            texts += [b" " + b" ".join(row) for row in zip(*columns)]
        data = splice(self.data, np.concatenate(starts), np.concatenate(ends), texts) if starts else bytes(self.data)
        if not new:
            return data
        return self._header_with(new) + data[self._header_end() :]

    def _header_end(self):
        """The offset of the line after end_header (the body's start)."""
        return header_end(self.data)[1]

    def _header_with(self, new):
        """The header with a ``property float NAME`` line per new name after the vertex element's last property
        (its line ending that of the line before it)."""
        header = self.data[: self._header_end()]
        lines = header.splitlines(keepends=True)
        words = [line.split() for line in lines]
        element = next(i for i, w in enumerate(words) if w[:2] == [b"element", b"vertex"])
        last = element
        for i in range(element + 1, len(words)):
            if words[i][:1] in ([b"element"], [b"end_header"]):
                break
            if words[i][:1] == [b"property"]:
                last = i
        ending = lines[last][len(lines[last].rstrip(b"\r\n")) :] or b"\n"
        added = [b"property float " + name.encode("ascii") + ending for name in new]
        return b"".join(lines[: last + 1] + added + lines[last + 1 :])


def _lengths(counts, element, prop, first=0):
    """The list lengths ``counts`` (of records ``first`` on) as int64; raises FormatError for one that is
    negative or, read from a float or double, not a whole number."""
    counts = np.asarray(counts)
    if counts.dtype.kind == "f":
        counts = integers(counts.astype(np.float64), f"PLY {element.name} {prop.name} list length")
    counts = counts.astype(np.int64)
    negative = np.flatnonzero(counts < 0)
    if negative.size:
        raise FormatError(
            f"PLY {element.name} record {first + negative[0]}: its {prop.name} list has a negative length "
            f"({counts[negative[0]]})"
        )
    return counts


def _gather(raw, offsets, dtype):
    """The values of ``dtype`` at byte ``offsets`` of ``raw``."""
    dtype = np.dtype(dtype)
    return raw[offsets[:, None] + np.arange(dtype.itemsize)].view(dtype).ravel()


def _record_starts(raw, position, element, order):
    """Byte offset of each record of ``element`` starting at ``position``.

    Records without list properties have one size. With lists, the records are taken in runs of equal
    list lengths (a mesh's faces are mostly one size): a run's records are checked in bulk, in windows
    that double while the run lasts."""
    sizes = [
        (np.dtype(p.type).itemsize, None if p.count_type is None else np.dtype(order + p.count_type), p)
        for p in element.properties
    ]
    if all(count is None for _, count, _ in sizes):
        return position + np.arange(element.count, dtype=np.int64) * sum(size for size, _, _ in sizes)
    runs = []
    done, window = 0, 16
    while done < element.count:
        # The list lengths of the record at ``position`` give its layout and size.
        layout, offset = [], 0
        for size, count, prop in sizes:
            if count is None:
                offset += size
                continue
            if position + offset + count.itemsize > len(raw):
                raise FormatError(f"PLY file ends inside its {element.name} records")
            at = position + offset
            length = int(_lengths(raw[at : at + count.itemsize].view(count), element, prop, done)[0])
            layout.append((offset, count, length))
            offset += count.itemsize + length * size
        record = offset
        # How many records from here have the same list lengths (and so the same size).
        limit = min(window, element.count - done, max(1, (len(raw) - position) // max(record, 1)))
        candidates = position + np.arange(limit, dtype=np.int64) * record
        same = np.ones(limit, dtype=bool)
        for at, count, length in layout:
            same &= _gather(raw, candidates + at, count) == length
        run = limit if same.all() else max(1, int(np.argmin(same)))
        runs.append(candidates[:run])
        done += run
        position += run * record
        window = window * 2 if run == limit else 16
    return np.concatenate(runs) if runs else np.zeros(0, dtype=np.int64)
