""".blend files for the command line: opened in Blender, their objects smoothed by the operators' own
code (operators/mesh_objects.py, operators/point_cloud.py, through the jobs the file route runs too) and
saved as a copy. The only part of the command that needs Blender; cli/command.py loads it for a .blend.
"""

import contextlib
import os
import signal
import threading

import bpy

from ..console_capture import captured
from ..operators import mesh_objects, point_cloud
from ..operators.objects import unique_data
from . import files
from .file_route import smooth_clouds, smooth_jobs
from .files import FileError


def ctrl_c_interrupts():
    """Make Ctrl+C raise KeyboardInterrupt again (after Blender loaded a file, which may set its own
    handler); only inside the command's ``interruptible`` span, on the main thread."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is not (
        signal.default_int_handler
    ):
        signal.signal(signal.SIGINT, signal.default_int_handler)


@contextlib.contextmanager
def in_blender(outcome):
    """Blender's part of a file, with what it prints collected into the outcome (shown if the file fails)."""
    lines = []
    try:
        with captured() as lines:
            yield
    finally:
        outcome.blender_lines.extend(lines)


def is_point_cloud(obj):
    return obj.type == "POINTCLOUD" or (obj.type == "MESH" and bool(len(obj.data.vertices)) and not len(obj.data.edges))


def smooth_blend_file(outcome, plan, settings, console):
    source = outcome.source
    console.stage(outcome, "reading", source)
    if not os.path.isfile(source):
        raise FileError("no such file")
    files.check_blend_version(files.blend_version(source), bpy.app.version)
    with in_blender(outcome):
        try:
            bpy.ops.wm.open_mainfile(filepath=os.path.abspath(source), load_ui=False)
            ctrl_c_interrupts()
        except RuntimeError as error:
            raise FileError(f"could not open the .blend file: {str(error).strip()}") from None
    files.check_blend_version(bpy.data.version, bpy.app.version)  # a header this could not read
    console.stage(outcome, "smoothing", source)
    if plan.objects:
        objects = []
        for name in plan.objects:
            obj = bpy.data.objects.get(name)
            if obj is None:
                raise FileError(f"no object '{name}' in this file")
            objects.append(obj)
    else:
        local = [obj for obj in bpy.data.objects if obj.library is None and obj.type in ("MESH", "POINTCLOUD")]
        objects = [obj for obj in local if is_point_cloud(obj) == plan.points]  # --points: the clouds, else the meshes
        others = [obj.name for obj in local if obj not in objects]
        if not objects:
            raise FileError(
                "no local point clouds (meshes without edges, point cloud objects) in this file"
                + (" (it has meshes: smooth them without --points)" if others else "")
                if plan.points
                else "no local mesh objects in this file" + (" (it has point clouds: pass --points)" if others else "")
            )
        if others:
            outcome.warnings.append(
                f"left as they are: {', '.join(sorted(others))} ("
                + (
                    "meshes: smooth them without --points)"
                    if plan.points
                    else "point clouds: smooth them with --points)"
                )
            )
    with in_blender(outcome):
        smooth_objects(objects, plan, settings, outcome)
    console.stage(outcome, "writing", outcome.target)
    with in_blender(outcome):
        files.save_blend_copy(outcome.target)


def smooth_objects(objects, plan, settings, outcome):
    """Smooth the objects as meshes, or as point clouds with --points; everything is read before anything is written."""
    if plan.points:
        smooth_point_clouds(objects, settings, outcome)
    else:
        smooth_meshes(objects, settings, outcome, plan.given)
    outcome.objects = len(objects)


def smooth_meshes(objects, settings, outcome, given=frozenset()):
    """A mesh shared by several objects is smoothed once. ``given``: the settings named on the command line."""
    for obj in objects:
        if obj.type != "MESH":
            raise FileError(
                f"'{obj.name}' is a {obj.type.lower().replace('_', ' ')} object, not a mesh"
                + (" (pass --points to smooth it)" if obj.type == "POINTCLOUD" else "")
            )
        if is_point_cloud(obj):
            raise FileError(f"'{obj.name}' has no edges: it is a point cloud (pass --points to smooth it as one)")
    jobs = [mesh_objects.make_job(obj, settings) for obj in unique_data(objects)]
    smooth_jobs(jobs, settings, outcome, given)
    mesh_objects.write_all(jobs, settings)


def smooth_point_clouds(objects, settings, outcome):
    """With the point operator's own functions (read, run, write), ``settings`` a point_cloud.PointSettings."""
    for obj in objects:
        if obj.type == "MESH" and (len(obj.data.edges) or len(obj.data.polygons)):
            raise FileError(f"'{obj.name}' has edges: it is a mesh, not a point cloud (smooth it without --points)")
    clouds = point_cloud.read_clouds(objects, settings)
    smooth_clouds(clouds, settings, outcome)
    point_cloud.write(clouds, settings, bpy.context)
