"""Reading and writing scan files with Blender's own importers/exporters, and writing atomically.

A result is first written to a hidden temporary file in the target folder and moved over the target
with os.replace only once it is complete, so a failure never leaves a half-written (or no longer
valid) output, and the target folder's relative paths (OBJ materials, .blend textures) stay right.

A result keeps its input's layout (see ``Layout``): the encoding, whether it has normals (recomputed
from the smoothed surface) and, for OBJ, whether it has a material library.
"""

import contextlib
import os
import re
import struct
from dataclasses import dataclass

import bpy
import numpy as np

# Blender's C++ importers/exporters (4.2+): operator name and the options that differ from defaults.
# The exporters' options that depend on the input are chosen by export_options().
IMPORTERS = {
    ".ply": ("ply_import", {}),
    ".obj": ("obj_import", {"import_vertex_groups": True}),  # OBJ groups can serve as --fixed-group
    ".stl": ("stl_import", {}),
}
EXPORTERS = {
    ".ply": ("ply_export", {"export_selected_objects": True}),
    ".obj": ("obj_export", {"export_selected_objects": True}),
    ".stl": ("stl_export", {"export_selected_objects": True}),
}


class FileError(Exception):
    """A message for the user about one file; its output was not written."""


@dataclass(frozen=True)
class Layout:
    """What a result takes over from its input file: read from the file's text, not from Blender."""

    ext: str
    ascii: bool = False  # PLY/STL in text rather than binary
    normals: bool = False  # PLY `nx ny nz` vertex properties, OBJ `vn` lines
    materials: bool = False  # OBJ `mtllib` lines


def read_layout(path):
    """The layout of the input file at ``path`` (raises OSError when it cannot be read)."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".ply":
        formats, properties = _ply_header(path)
        return Layout(ext, ascii="ascii" in formats, normals={"nx", "ny", "nz"} <= properties)
    if ext == ".stl":
        return Layout(ext, ascii=_stl_is_ascii(path))
    if ext == ".obj":
        found = _obj_statements(path, (b"vn", b"mtllib"))
        return Layout(ext, normals=b"vn" in found, materials=b"mtllib" in found)
    return Layout(ext)


def _ply_header(path, limit=1 << 20):
    """The PLY header's format words (`ascii`, `binary_little_endian`, ...) and its vertex properties' names."""
    with open(path, "rb") as file:
        header = file.read(limit).split(b"end_header", 1)[0].decode("ascii", "replace")
    formats, properties, element = set(), set(), None
    for line in header.splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] == "format":
            formats.add(words[1])
        elif len(words) >= 2 and words[0] == "element":
            element = words[1]
        elif len(words) >= 3 and words[0] == "property" and element == "vertex":
            properties.add(words[-1])
    return formats, properties


def _stl_is_ascii(path):
    """A binary STL is 84 bytes plus 50 per triangle (its 80-byte header may itself start with `solid`)."""
    with open(path, "rb") as file:
        start = file.read(84)
        size = os.fstat(file.fileno()).st_size
    if len(start) == 84 and size == 84 + 50 * struct.unpack("<I", start[80:84])[0]:
        return False
    return start.lstrip().startswith(b"solid")


def _obj_statements(path, keywords, chunk=1 << 24):
    """Which of ``keywords`` start a line of the OBJ file: a plain byte search, the file is not parsed."""
    needles = {keyword: [b"\n" + keyword + space for space in (b" ", b"\t")] for keyword in keywords}
    overlap = max(len(needle) for group in needles.values() for needle in group) - 1
    found = set()
    with open(path, "rb") as file:
        data = b"\n"  # the first line starts after a newline too
        while len(found) < len(needles):
            block = file.read(chunk)
            if not block:
                break
            data = data[-overlap:] + block  # a statement cut by the chunk boundary is found whole
            found.update(keyword for keyword, group in needles.items() if any(needle in data for needle in group))
    return found


def import_file(path, result_ext=None):
    """Import a PLY/OBJ/STL file into the current (empty) scene; returns the new objects.

    ``result_ext`` is the format the result will be written in: PLY colours go to a PLY result as
    stored (Blender's sRGB conversion there and back darkens them by a step in 255 each run)."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in IMPORTERS:
        raise FileError(f"unsupported file type '{ext}' (PLY, OBJ, STL or .blend)")
    if not os.path.isfile(path):
        raise FileError("no such file")
    name, options = IMPORTERS[ext]
    if ext == ".ply" and result_ext == ".ply":
        options = {**options, "import_colors": "LINEAR"}
    before = set(bpy.data.objects)
    try:
        result = getattr(bpy.ops.wm, name)(filepath=os.path.abspath(path), **options)
    except RuntimeError as error:  # the importer's own error report
        raise FileError(f"could not read the file: {str(error).strip()}") from None
    objects = [obj for obj in bpy.data.objects if obj not in before]
    if result != {"FINISHED"} or not objects:
        raise FileError("the importer read nothing from this file")
    return objects


def temporary_path(target):
    """A hidden sibling of ``target`` with the same extension (exporters may insist on it)."""
    folder, base = os.path.split(target)
    stem, ext = os.path.splitext(base)
    return os.path.join(folder, f".{stem}.hc_smooth-{os.getpid()}{ext}")


# temporary_path's names, with the exporter's .mtl, the .tmp of _rename_material_library and Blender's
# own save temporary (name@); the pid is what tells whether the run that wrote it is still going.
TEMPORARY = re.compile(r"^\..+\.hc_smooth-([1-9][0-9]*)\.(?:ply|obj|stl|mtl|blend)(?:\.tmp|@)?$", re.IGNORECASE)


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


def export_options(ext, layout, objects):
    """The exporter's options for a result in format ``ext`` of an input with ``layout``.

    The encoding carries over when the format stays (--format gives the exporter's default, binary);
    normals and the material library go out only when the input had them; OBJ colours whenever the
    meshes have colours (PLY writes them by default). UVs and other attributes: the exporters' defaults."""
    meshes = [obj.data for obj in objects if obj.type == "MESH"]
    same = layout.ext == ext
    if ext == ".ply":
        # Vertices without faces have no surface normal: Blender would write made-up ones (see _point_normals).
        surface = any(len(mesh.polygons) for mesh in meshes)
        return {
            "ascii_format": same and layout.ascii,
            "export_normals": layout.normals and surface,
            "export_colors": "LINEAR" if same else "SRGB",
        }  # LINEAR: as import_file read them
    if ext == ".obj":
        return {
            "export_normals": layout.normals,
            "export_materials": layout.materials,
            "export_colors": any(len(mesh.color_attributes) for mesh in meshes),
        }
    return {"ascii_format": same and layout.ascii}


def _recompute_normals(objects):
    """Drop the normals the importer stored (custom normals, the input's): the exporter then writes the
    normals of the smoothed surface."""
    for obj in objects:
        if obj.type == "MESH" and obj.data.has_custom_normals:
            with bpy.context.temp_override(object=obj, active_object=obj):
                bpy.ops.mesh.customdata_custom_splitnormals_clear()


def _point_normals(objects):
    """A PLY point cloud's normals (the importer's `normal` attribute) back under their PLY names nx, ny, nz.

    Points have no surface to recompute normals from, so the input's are kept; the exporter would
    write the attribute as normal_x, normal_y, normal_z."""
    for obj in objects:
        mesh = obj.data
        normal = mesh.attributes.get("normal") if obj.type == "MESH" and not len(mesh.polygons) else None
        if (
            normal is None
            or normal.data_type != "FLOAT_VECTOR"
            or normal.domain != "POINT"
            or any(name in mesh.attributes for name in ("nx", "ny", "nz"))
        ):
            continue
        values = np.empty(3 * len(mesh.vertices), dtype=np.float32)
        normal.data.foreach_get("vector", values)
        for axis, name in enumerate(("nx", "ny", "nz")):
            mesh.attributes.new(name, "FLOAT", "POINT").data.foreach_set("value", values[axis::3])
        mesh.attributes.remove(mesh.attributes["normal"])


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


def export_file(objects, target, layout):
    """Export ``objects`` to ``target`` (format from its extension) in the ``layout`` of the input, atomically."""
    ext = os.path.splitext(target)[1].lower()
    name, options = EXPORTERS[ext]
    options = {**options, **export_options(ext, layout, objects)}
    _recompute_normals(objects)
    if ext == ".ply":
        _point_normals(objects)
    for obj in bpy.context.scene.objects:
        obj.select_set(obj in objects)
    bpy.context.view_layer.objects.active = objects[0]
    with _target_folder(target):
        _export(name, options, target, ext)


def _export(name, options, target, ext):
    temporary = temporary_path(target)
    companions = {temporary[: -len(ext)] + ".mtl": target[: -len(ext)] + ".mtl"} if ext == ".obj" else {}
    try:
        try:
            result = getattr(bpy.ops.wm, name)(filepath=temporary, **options)
        except RuntimeError as error:
            raise FileError(f"could not write {target}: {str(error).strip()}") from None
        if result != {"FINISHED"} or not os.path.isfile(temporary):
            raise FileError(f"the exporter wrote nothing to {target}")
        if ext == ".obj":
            _rename_material_library(temporary, companions)
        for temp, final in companions.items():
            if os.path.exists(temp):
                os.replace(temp, final)
        os.replace(temporary, target)  # last: the main file appears only when everything is in place
    finally:
        for leftover in (temporary, *companions):
            if os.path.exists(leftover):
                os.remove(leftover)


def _rename_material_library(obj_path, companions):
    """The OBJ exporter names its .mtl after the temporary file: point `mtllib` at the final name."""
    ((temp_mtl, final_mtl),) = companions.items()
    if not os.path.exists(temp_mtl):
        return
    old = f"mtllib {os.path.basename(temp_mtl)}".encode()
    new = f"mtllib {os.path.basename(final_mtl)}".encode()
    fixed = obj_path + ".tmp"
    try:
        with open(obj_path, "rb") as source, open(fixed, "wb") as out:
            for line in source:  # the mtllib line is in the header; the rest is copied as is
                if line.startswith(old):
                    out.write(new + line[len(old) :])
                    out.write(source.read())
                    break
                out.write(line)
        os.replace(fixed, obj_path)
    finally:
        if os.path.exists(fixed):
            os.remove(fixed)


def save_blend_copy(target):
    """Save the open .blend as a copy at ``target``, atomically (relative paths remapped to its folder)."""
    with _target_folder(target):
        _save_blend_copy(target)


def _save_blend_copy(target):
    temporary = temporary_path(target)
    try:
        try:
            bpy.ops.wm.save_as_mainfile(filepath=temporary, copy=True, relative_remap=True, check_existing=False)
        except RuntimeError as error:
            raise FileError(f"could not save {target}: {str(error).strip()}") from None
        os.replace(temporary, target)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)
