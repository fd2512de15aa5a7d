"""Whitespace-separated text read and rewritten with NumPy: the ASCII formats (PLY, OBJ, STL) without a
Python loop per line.

A text is seen as its tokens (byte spans between whitespace). Readers pick the tokens they need by
index and parse them in bulk; writers replace some tokens' text and keep every other byte.
"""

import warnings

import numpy as np

WHITESPACE = np.zeros(256, dtype=bool)
WHITESPACE[[9, 10, 11, 12, 13, 32]] = True


class FormatError(Exception):
    """A file this reader cannot take, with the reason for the user."""


class Tokens:
    """The tokens of ``data[start:end]``: ``starts``/``ends`` (byte offsets into ``data``) and ``lines``
    (the line number of each token, counted from ``start``)."""

    def __init__(self, data, start=0, end=None):
        self.data = data
        self.bytes = np.frombuffer(data, dtype=np.uint8)
        text = self.bytes[start:end]
        space = WHITESPACE[text]
        # +1 where a token starts, -1 just after it ends.
        change = np.diff(np.concatenate(([1], space.view(np.int8), [1])).astype(np.int8))
        self.starts = np.flatnonzero(change == -1) + start
        self.ends = np.flatnonzero(change == 1) + start
        newlines = np.flatnonzero(text == 10) + start
        self.lines = np.searchsorted(newlines, self.starts)

    def __len__(self):
        return len(self.starts)

    def text(self, index):
        """The token texts at ``index`` joined by single spaces (one trailing space)."""
        return gather(self.bytes, self.starts[index], self.ends[index])

    def numbers(self, index, what):
        """The tokens at ``index`` as float64; raises FormatError naming ``what`` if one is not a number."""
        index = np.asarray(index)
        if index.size == 0:
            return np.zeros(index.shape)
        values = parse_numbers(self.text(index.ravel()), index.size, what)
        return values.reshape(index.shape)

    def first_bytes(self, index, width):
        """(len(index), width) array of each token's first ``width`` bytes (0 past the token's end)."""
        starts, ends = self.starts[index], self.ends[index]
        offsets = starts[:, None] + np.arange(width)
        inside = offsets < ends[:, None]
        return np.where(inside, self.bytes[np.minimum(offsets, len(self.bytes) - 1)], 0)

    def is_word(self, index, word):
        """Which tokens at ``index`` are ``word`` (ASCII letters in any case)."""
        index = np.asarray(index)
        length = self.ends[index] - self.starts[index]
        heads = self.first_bytes(index, len(word)) | 0x20  # lower case for letters
        return (length == len(word)) & np.all(heads == np.frombuffer(word.lower(), np.uint8), axis=1)


def gather(array, starts, ends, separator=32):
    """The byte spans [starts[i], ends[i]) of ``array``, each followed by ``separator``, as bytes."""
    lengths = ends - starts
    count = len(lengths)
    inner = int(lengths.sum())
    out = np.full(inner + count, separator, dtype=np.uint8)
    before = np.cumsum(lengths) - lengths  # where each span starts among the spans' bytes
    step = np.arange(inner)
    out[step + np.repeat(np.arange(count), lengths)] = array[step + np.repeat(starts - before, lengths)]
    return out.tobytes()


def parse_numbers(text, count, what):
    """``count`` whitespace-separated numbers of ``text`` as float64 (nan and inf parse as such)."""
    try:
        with warnings.catch_warnings():
            # NumPy < 2.5 warns and stops at a word that is not a number (counted below); 2.5 raises.
            warnings.simplefilter("ignore", DeprecationWarning)
            values = np.fromstring(text, dtype=np.float64, sep=" ")
    except ValueError:
        values = np.zeros(0)
    if len(values) != count:
        bad = next((word for word in text.split() if not _is_number(word)), b"?")
        raise FormatError(f"{what}: '{bad.decode('ascii', 'replace')}' is not a number")
    return values


def _is_number(word):
    try:
        float(word)
    except ValueError:
        return False
    return True


def integers(values, what):
    """float64 values read from text as int64; raises FormatError if one is not a whole number."""
    whole = np.isfinite(values) & (values == np.round(values)) & (np.abs(values) < 2.0**53)
    if not whole.all():
        raise FormatError(f"{what}: {values[~whole][0]:g} is not a whole number")
    return values.astype(np.int64)


def number_texts(values, dtype):
    """The shortest text of each value that reads back to it exactly in ``dtype`` (float32 or float64)."""
    return np.asarray(values, dtype=dtype).astype(bytes).tolist()


def splice(data, starts, ends, texts):
    """``data`` with each span [starts[i], ends[i]) replaced by texts[i]; spans sorted, not overlapping."""
    if len(starts) == 0:
        return bytes(data)
    order = np.argsort(starts, kind="stable")
    starts, ends = np.asarray(starts)[order], np.asarray(ends)[order]
    texts = [texts[i] for i in order.tolist()]
    view = memoryview(data)
    keep_from = [0, *ends.tolist()]
    keep_to = [*starts.tolist(), len(data)]
    pieces = [None] * (2 * len(texts) + 1)
    pieces[0::2] = [view[a:b] for a, b in zip(keep_from, keep_to)]
    pieces[1::2] = texts
    return b"".join(pieces)
