"""Reading and writing scan files with Blender's own importers/exporters, and writing atomically.

A result is first written to a hidden temporary file in the target folder and moved over the target
with os.replace only once it is complete, so a failure never leaves a half-written (or no longer
valid) output, and the target folder's relative paths (OBJ materials, .blend textures) stay right.
"""

import os
import re

import bpy

# Blender's C++ importers/exporters (4.2+): operator name and the options that differ from defaults.
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


def import_file(path):
    """Import a PLY/OBJ/STL file into the current (empty) scene; returns the new objects."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in IMPORTERS:
        raise FileError(f"unsupported file type '{ext}' (PLY, OBJ, STL or .blend)")
    if not os.path.isfile(path):
        raise FileError("no such file")
    name, options = IMPORTERS[ext]
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


def export_file(objects, target):
    """Export ``objects`` to ``target`` (format from its extension), atomically."""
    ext = os.path.splitext(target)[1].lower()
    name, options = EXPORTERS[ext]
    for obj in bpy.context.scene.objects:
        obj.select_set(obj in objects)
    bpy.context.view_layer.objects.active = objects[0]
    temporary = temporary_path(target)
    companions = {temporary[:-len(ext)] + ".mtl": target[:-len(ext)] + ".mtl"} if ext == ".obj" else {}
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
    (temp_mtl, final_mtl), = companions.items()
    if not os.path.exists(temp_mtl):
        return
    old = f"mtllib {os.path.basename(temp_mtl)}".encode()
    new = f"mtllib {os.path.basename(final_mtl)}".encode()
    fixed = obj_path + ".tmp"
    try:
        with open(obj_path, "rb") as source, open(fixed, "wb") as out:
            for line in source:  # the mtllib line is in the header; the rest is copied as is
                if line.startswith(old):
                    out.write(new + line[len(old):])
                    out.write(source.read())
                    break
                out.write(line)
        os.replace(fixed, obj_path)
    finally:
        if os.path.exists(fixed):
            os.remove(fixed)


def save_blend_copy(target):
    """Save the open .blend as a copy at ``target``, atomically (relative paths remapped to its folder)."""
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
