"""Keep the demo's console readable: what Blender's C code prints (render progress, save notices,
operator reports) is collected instead of interleaving with the demo's own lines."""

import contextlib
import ctypes
import os
import sys
import tempfile


def _flush():
    """Flush Python's and the C library's buffers: Blender prints with printf."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    try:
        (ctypes.CDLL(None) if os.name == "posix" else ctypes.CDLL("ucrtbase")).fflush(None)
    except (OSError, AttributeError):  # no C library to reach: its buffered lines may come out later
        pass


@contextlib.contextmanager
def captured():
    """Collect everything written to file descriptors 1 and 2 and to sys.stdout/sys.stderr while the
    block runs; yields a list that holds those lines (blank ones dropped) once the block is done."""
    lines = []
    _flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as buffer:
        stream = open(buffer.fileno(), "w", encoding="utf-8", errors="replace", buffering=1, closefd=False)
        try:
            os.dup2(buffer.fileno(), 1)
            os.dup2(buffer.fileno(), 2)
            with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
                yield lines
        finally:
            stream.close()
            _flush()
            for fd, copy in zip((1, 2), saved, strict=True):
                os.dup2(copy, fd)
                os.close(copy)
            buffer.seek(0)
            lines.extend(line for line in buffer.read().decode("utf-8", "replace").splitlines() if line.strip())
