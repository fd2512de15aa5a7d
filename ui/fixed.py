"""Which vertices the operator will keep fixed, counted for the panel.

The count comes from the operator's own reader (operators.mesh_objects.make_job), so the panel and the run
agree by construction, including the reasons a run would refuse (missing group, no edges, NaN...).
Counting reads the whole mesh as a run would, which draw() must not repeat: counts are cached per
mesh state, filled automatically for small meshes and by a button for large ones, and dropped
whenever Blender reports a geometry change.
"""

import bmesh
import bpy
import numpy as np

from ..jobs import mesh as mesh_jobs
from ..operators import mesh_objects, objects

# Meshes up to this size are counted on first draw; larger ones when the user presses the button.
AUTO_COUNT_LIMIT = 100_000

_counts = {}  # key -> (n_fixed, n_vertices) or an error message


def _key(obj, settings):
    mesh = obj.data
    group = obj.vertex_groups.get(settings.vertex_group) if settings.vertex_group else None
    return (
        mesh.as_pointer(),
        len(mesh.vertices),
        len(mesh.edges),
        settings.vertex_group,
        None if group is None else group.index,
        settings.invert_vertex_group,
        settings.pin_boundary,
        settings.keep_outline,  # its rule holds the corners where boundaries meet
    )


def cached(obj, settings):
    """(n_fixed, n_vertices), an error message, or None when not counted yet."""
    return _counts.get(_key(obj, settings))


def count(obj, settings):
    """Count the fixed vertices of ``obj`` (Object mode data) as the operator would, and cache it."""
    key = _key(obj, settings)
    try:
        job = mesh_objects.make_job(obj, settings)
    except objects.InputError as error:
        _counts[key] = str(error)
        return _counts[key]
    still = mesh_jobs.make_smoother(job, mesh_jobs.core_options(settings)).still()  # the run's own rules
    _counts[key] = (int(np.count_nonzero(still)), len(job.positions))
    return _counts[key]


def should_count_now(obj):
    return len(obj.data.vertices) <= AUTO_COUNT_LIMIT


def edit_mode_selection(objects):
    """(selected, total) vertices of meshes in Edit mode, from BMesh counters (no per-vertex work)."""
    selected = total = 0
    for obj in objects:
        selected += obj.data.total_vert_sel
        total += len(bmesh.from_edit_mesh(obj.data).verts)
    return selected, total


# persistent: Blender drops other handlers whenever a file is loaded, which would leave stale counts.
@bpy.app.handlers.persistent
def clear(*_args):
    _counts.clear()


@bpy.app.handlers.persistent
def _on_depsgraph_update(_scene, depsgraph):
    if any(update.is_updated_geometry for update in depsgraph.updates):
        _counts.clear()


class HC_SMOOTH_OT_count_fixed(bpy.types.Operator):
    """Count the vertices HC Smooth will keep fixed on the active object (reads its vertex group)"""

    bl_idname = "hc_smooth.count_fixed"
    bl_label = "Count Fixed Vertices"
    bl_options = {"INTERNAL"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return context.mode == "OBJECT" and obj is not None and obj.type == "MESH"

    def execute(self, context):
        count(context.active_object, context.scene.hc_smooth)
        for area in context.screen.areas if context.screen else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()
        return {"FINISHED"}


classes = (HC_SMOOTH_OT_count_fixed,)

_HANDLERS = (
    (bpy.app.handlers.depsgraph_update_post, _on_depsgraph_update),
    (bpy.app.handlers.load_post, clear),
    (bpy.app.handlers.undo_post, clear),
    (bpy.app.handlers.redo_post, clear),
)


def register():
    for handlers, function in _HANDLERS:
        handlers.append(function)


def unregister():
    for handlers, function in _HANDLERS:
        if function in handlers:
            handlers.remove(function)
    _counts.clear()
