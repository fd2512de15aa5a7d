"""The command's files: scan files read and written with our own readers (cli/formats), .blend files
checked and saved, and every result written atomically.

A result is first written to a hidden temporary file in the target folder and moved over the target
with os.replace only once it is complete, so a failure or an interrupt never leaves a half-written
(or no longer valid) output. A scan file's result is its input with the smoothed positions (and the
normals it carries) written in; nothing else changes, and nothing is written beside it (an OBJ's
.mtl and textures stay as they are).
"""

import contextlib
import gzip
import os
import re
import secrets

from . import formats

BLEND_MAGIC = b"BLENDER"
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
GZIP_MAGIC = b"\x1f\x8b"


class FileError(Exception):
    """A message for the user about one file; its output was not written."""


def read_mesh(path):
    """The PLY/OBJ/STL file at ``path`` parsed and checked (cli/formats); raises FileError."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in formats.READERS:
        raise FileError(f"unsupported file type '{ext}' (PLY, OBJ, STL or .blend)")
    if not os.path.isfile(path):
        raise FileError("no such file")
    try:
        return formats.read(path)
    except formats.FormatError as error:
        raise FileError(str(error)) from None
    except OSError as error:
        raise FileError(f"could not read the file: {error.strerror or error}") from None


def result_bytes(mesh, result, target, added=None):
    """The bytes of the result file: the input with ``result`` written in, or in another format (--format);
    ``added``: {name: one float per vertex} to store as vertex properties (PLY only)."""
    ext = os.path.splitext(target)[1].lower()
    try:
        if ext == mesh.ext:
            return formats.updated(mesh, result, added)
        return formats.converted(mesh, result, ext, added)
    except formats.FormatError as error:
        raise FileError(str(error)) from None


def temporary_path(target):
    """A hidden sibling of ``target`` with the same extension, `.hc_smooth-<pid>-<random>.<ext>`: short, so
    that it fits wherever the target's name fits."""
    folder = os.path.dirname(target)
    return os.path.join(folder, f".hc_smooth-{os.getpid()}-{secrets.token_hex(4)}{os.path.splitext(target)[1]}")


# temporary_path's names, the `.<name>.hc_smooth-<pid>.<ext>` ones (with .mtl and .tmp) of earlier
# versions, and Blender's own save temporary (name@); the pid tells whether the run that wrote it is still going.
TEMPORARY = re.compile(
    r"^\.(?:.+\.)?hc_smooth-([1-9][0-9]*)(?:-[0-9a-f]+)?\.(?:ply|obj|stl|mtl|blend)(?:\.tmp|@)?$", re.IGNORECASE
)


def _running(pid):
    """False only when no process ``pid`` exists; anything uncertain counts as running."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)  # signal 0: nothing is sent, only whether the process exists is checked
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # PermissionError: it exists, under another user
        return True
    return True


def remove_stale_temporaries(folder):
    """Remove our temporaries in ``folder`` whose process no longer runs (a killed run); returns their names.

    A file whose process may still be running (another run writing into the same folder) is kept."""
    if os.name != "posix":  # elsewhere os.kill(pid, 0) would terminate the process rather than test it
        return []
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:  # an unreadable folder: writing into it will say what is wrong
        return []
    for entry in entries:
        match = TEMPORARY.match(entry.name)
        if match is None or not entry.is_file(follow_symlinks=False) or _running(int(match.group(1))):
            continue
        try:
            os.remove(entry.path)
        except OSError:  # gone already (another run cleaned up first) or not ours to remove: leave it
            continue
        removed.append(entry.name)
    return sorted(removed)


@contextlib.contextmanager
def _target_folder(target):
    """Create the folder of ``target`` (and missing parents) for a write; if the write fails, remove the
    folders this created that stayed empty, so a failed run leaves no empty output folder behind."""
    folder = os.path.dirname(os.path.abspath(target))
    created, path = [], folder
    while not os.path.isdir(path) and os.path.dirname(path) != path:
        created.append(path)  # deepest first
        path = os.path.dirname(path)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as error:
        raise FileError(f"could not create the folder {folder}: {error.strerror or error}") from None
    try:
        yield
    except BaseException:
        for path in created:
            try:
                os.rmdir(path)  # only an empty folder: another result may have landed there meanwhile
            except OSError:
                break
        raise


@contextlib.contextmanager
def _replacing(target):
    """Yield a temporary path to write; on success it replaces ``target`` (keeping the permission bits
    of the file it replaces), on any failure or interrupt it is removed."""
    temporary = temporary_path(target)
    try:
        yield temporary
        if os.path.exists(target):
            with contextlib.suppress(OSError):
                os.chmod(temporary, os.stat(target).st_mode & 0o7777)
        os.replace(temporary, target)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


@contextlib.contextmanager
def written(target):
    """A temporary path for a writer that builds ``target`` in place (a copy written into): moved over
    ``target`` once the block ends, removed (with the folders made for it) if it fails or is interrupted."""
    with _target_folder(target), _replacing(target) as temporary:
        yield temporary


def write_bytes(target, data):
    """Write ``data`` to ``target`` atomically (created folders removed again if it fails)."""
    with _target_folder(target), _replacing(target) as temporary:
        try:
            with open(temporary, "wb") as file:
                file.write(data)
        except OSError as error:
            raise FileError(f"could not write {target}: {error.strerror or error}") from None


# --- .blend files ---------------------------------------------------------------------------------


def blend_version(path):
    """The version of Blender that saved the .blend at ``path`` as (major, minor), from its header; None
    when the header cannot be read here (zstd compression without the zstandard module)."""
    with open(path, "rb") as file:
        start = file.read(64)
        if start.startswith(GZIP_MAGIC):
            file.seek(0)
            with gzip.open(file) as unpacked:
                start = unpacked.read(64)
        elif start.startswith(ZSTD_MAGIC):
            try:
                import zstandard  # bundled with Blender
            except ImportError:
                return None
            file.seek(0)
            with zstandard.ZstdDecompressor().stream_reader(file) as unpacked:
                start = unpacked.read(64)
    return header_version(start)


def header_version(start):
    """(major, minor) from a .blend header: `BLENDER_v405` (three digits, before Blender 5.0) or
    `BLENDER17-01v0502` (a header size and format, then four digits); None if it is not a .blend."""
    if not start.startswith(BLEND_MAGIC):
        return None
    old = re.match(rb"BLENDER[_-][vV](\d)(\d\d)", start)
    if old:
        return int(old.group(1)), int(old.group(2))
    new = re.match(rb"BLENDER\d\d-\d\d[vV](\d\d)(\d\d)", start)
    if new:
        return int(new.group(1)), int(new.group(2))
    return None


def check_blend_version(saved, running):
    """Refuse a .blend saved by a newer Blender: writing it back would drop what this one does not know."""
    if saved is not None and tuple(saved[:2]) > tuple(running[:2]):
        raise FileError(
            f"saved by Blender {saved[0]}.{saved[1]}, newer than this Blender "
            f"({running[0]}.{running[1]}): saving it here could lose data; smooth it with Blender "
            f"{saved[0]}.{saved[1]} or newer"
        )


def save_blend_copy(target):
    """Save the open .blend as a copy at ``target``, atomically (relative paths remapped to its folder)."""
    import bpy

    with _target_folder(target), _replacing(target) as temporary:
        try:
            bpy.ops.wm.save_as_mainfile(filepath=temporary, copy=True, relative_remap=True, check_existing=False)
        except RuntimeError as error:
            raise FileError(f"could not save {target}: {str(error).strip()}") from None
