"""Collect what Blender prints while a block runs, so a person's console shows only the lines meant
for them (the command line's per-file progress, the demo's table).

Plain Python, no imports from the rest of the package: the command line (cli/command.py) and the
operators (operators/undo_steps.py) use it, and so do scripts that run before the add-on is installed
(demo/demo.py imports ``console_capture`` with the repository root on sys.path).
"""

import contextlib
import ctypes
import os
import sys
import tempfile


def _flush_output():
    """Flush Python's and the C library's stdout/stderr buffers (Blender prints with printf)."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    try:
        libc = ctypes.CDLL(None) if os.name == "posix" else ctypes.CDLL("ucrtbase")
        libc.fflush(None)
    except (OSError, AttributeError):  # no C library to reach: what it buffered may come out later
        pass


@contextlib.contextmanager
def captured():
    """Collect what Blender prints (file descriptors 1 and 2, where its C code writes, and Python's
    sys.stdout/sys.stderr) while the block runs.

    Yields a list that holds the printed lines once the block is done; the console sees none of them.
    Without temporary space or real file descriptors (an embedding that closed them) nothing is collected."""
    lines = []
    buffer, saved = None, []
    try:
        buffer = tempfile.TemporaryFile()
        saved = [os.dup(1)]
        saved.append(os.dup(2))
    except OSError:
        for copy in saved:
            os.close(copy)
        saved = []
    if not saved:  # Blender's lines go to the console as they come
        if buffer is not None:
            buffer.close()
        yield lines
        return
    _flush_output()  # what was printed before goes to the console first
    # Operator reports go through Python's sys.stdout, which need not write to descriptor 1: same file.
    stream = open(buffer.fileno(), "w", encoding="utf-8", errors="replace", buffering=1, closefd=False)
    try:
        os.dup2(buffer.fileno(), 1)
        os.dup2(buffer.fileno(), 2)
        with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
            yield lines
    finally:
        stream.close()
        _flush_output()
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)
        with buffer:
            buffer.seek(0)
            lines.extend(line for line in buffer.read().decode("utf-8", "replace").splitlines() if line.strip())
