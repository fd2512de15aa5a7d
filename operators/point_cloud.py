"""object.hc_smooth_points: smooth point clouds (meshes of loose vertices, PointCloud objects) through
their RFS mesh (paper section 7, core.smooth_point_cloud).

Thin like the mesh operators: read every selected cloud, validate, smooth, and only then write, so a
failure leaves everything as it was. execute() depends only on the properties and the objects, so the
redo panel (F9) can re-run it. The steps are plain functions of a ``PointSettings``: read_clouds and write
here, run and messages in jobs/points.py, which the command line (cli/) calls too.
"""

import bpy
import numpy as np

from .. import settings_spec
from ..jobs import points
from ..jobs.points import Cloud, lowest_alpha, make_smoother, messages, run
from ..settings_spec import PointSettings
from . import mesh_io, objects
from .draw import draw_convergence, draw_settings
from .modal_progress import ModalProgress
from .objects import InputError, unique_data
from .properties import annotations, set_by_caller

POINT_TYPES = ("MESH", "POINTCLOUD")


def _attribute_mask(data, name, count):
    """Point-domain boolean/float/int attribute as a mask (value != 0), or None if there is none."""
    attribute = data.attributes.get(name)
    if attribute is None or attribute.domain != "POINT":
        return None
    kinds = {"BOOLEAN": (bool, "value"), "FLOAT": (np.float32, "value"), "INT": (np.int32, "value")}
    if attribute.data_type not in kinds:
        return None
    dtype, key = kinds[attribute.data_type]
    values = np.empty(count, dtype=dtype)
    attribute.data.foreach_get(key, values)
    return values != 0


class ObjectCloud(Cloud):
    """A Blender object's cloud: where its points come from and go to."""

    def __init__(self, obj, settings):
        if obj.type not in POINT_TYPES:
            raise InputError(
                f"'{obj.name}' is a {obj.type.lower().replace('_', ' ')} object: "
                "select a mesh of loose vertices or a point cloud"
            )
        objects.check_editable(obj)
        self.obj, self.data = obj, obj.data
        count = len(obj.data.vertices) if obj.type == "MESH" else len(obj.data.points)
        if count == 0:
            raise InputError(f"'{obj.data.name}' has no points: nothing to smooth")
        if obj.type == "MESH" and (len(obj.data.edges) or len(obj.data.polygons)):
            raise InputError(
                f"Mesh '{obj.data.name}' has edges or faces: HC Smooth Points works on loose "
                "vertices. Use HC Smooth (object.hc_smooth) for meshes"
            )
        positions, self.key_block = objects.read_positions(obj, noun=("point", "points"))
        super().__init__(obj.data.name, positions)
        self.fixed = self._fixed(settings)

    def _fixed(self, settings):
        n = len(self.positions)
        if not settings.vertex_group:
            return None
        if self.obj.type == "MESH":
            group = self.obj.vertex_groups.get(settings.vertex_group)
            if group is None:
                raise InputError(f"Object '{self.obj.name}' has no vertex group '{settings.vertex_group}'")
            members = mesh_io.vertex_group_members(self.obj, group.index)
        else:  # point clouds have no vertex groups: a point attribute of that name plays the part
            members = _attribute_mask(self.data, settings.vertex_group, n)
            if members is None:
                raise InputError(
                    f"Point cloud '{self.data.name}' has no point attribute '{settings.vertex_group}' "
                    "(boolean, integer or float) to use as the fixed group"
                )
        return ~members if settings.invert_vertex_group else members

    def write(self):
        objects.write_positions(self.obj, self.key_block, self.positions, self.result)

    def add_rfs_object(self, context):
        """The final RFS mesh at the smoothed positions, as a new object beside the cloud."""
        mesh = bpy.data.meshes.new(self.obj.name + " RFS")
        faces = self.report.mesh.faces
        mesh.vertices.add(len(self.result))
        mesh.vertices.foreach_set("co", np.ascontiguousarray(self.result, np.float32).ravel())
        mesh.loops.add(faces.size)
        mesh.loops.foreach_set("vertex_index", faces.astype(np.int32).ravel())
        mesh.polygons.add(len(faces))
        mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
        mesh.polygons.foreach_set("loop_total", np.full(len(faces), 3, dtype=np.int32))
        mesh.update(calc_edges=True)
        mesh.validate(clean_customdata=False)
        obj = bpy.data.objects.new(mesh.name, mesh)
        obj.matrix_world = self.obj.matrix_world.copy()
        for collection in self.obj.users_collection or (context.scene.collection,):
            collection.objects.link(obj)
        obj.display_type = "WIRE"
        return obj


def read_clouds(selected, settings):
    """Read and check every object (an object data shared by several objects once); raises InputError. Reads only."""
    points.check_settings(settings)
    return [ObjectCloud(obj, settings) for obj in unique_data(selected)]


def write(clouds, settings, context):
    """Write every result (and the RFS meshes if asked for); call only once ``run`` has finished."""
    for cloud in clouds:
        cloud.write()
        if settings.keep_rfs_mesh:
            cloud.add_rfs_object(context)


class OBJECT_OT_hc_smooth_points(ModalProgress, bpy.types.Operator):
    """Smooth point clouds (meshes of loose vertices, point cloud objects) without shrinking them: HC steps on a temporary RFS mesh, alternating with edge swapping"""  # noqa: E501 - Blender's tooltip: one line

    bl_idname = "object.hc_smooth_points"
    bl_label = "HC Smooth Points"
    bl_options = {"REGISTER", "UNDO"}
    progress_label = "HC Smooth Points"

    __annotations__ = annotations(settings_spec.POINTS)

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        given = set_by_caller(self, settings_spec.SWITCHES_OFF_THE_AMOUNT)
        draw_settings(layout, self, settings_spec.POINTS, context.active_object, given=given)
        draw_convergence(layout, "HC", lowest_alpha(self, given), self.beta)

    def _clouds(self, context, settings):
        objects = [obj for obj in context.selected_objects if obj.type in POINT_TYPES]
        if not objects:
            others = ", ".join(sorted({obj.type.lower() for obj in context.selected_objects}))
            raise InputError(
                "Select a mesh of loose vertices or a point cloud object" + (f" (selected: {others})" if others else "")
            )
        return read_clouds(objects, settings)

    def _finish(self, context, clouds, settings):
        write(clouds, settings, context)
        for level, text in messages(clouds, settings):
            self.report({level}, text)
        return {"FINISHED"}

    def snapshot(self):
        """The settings this run reads (a modal run must not see later edits). Alpha or Steps per Round
        set by the caller are used as set: the Automatic Amount chooses only what was left unset."""
        settings = PointSettings.of(self)
        given = set_by_caller(self, settings_spec.SWITCHES_OFF_THE_AMOUNT)
        settings.auto_amount = settings_spec.automatic(settings_spec.values_of(settings, settings_spec.POINTS), given)
        return settings

    def execute(self, context):
        settings = self.snapshot()
        try:
            clouds = self._clouds(context, settings)
            for _ in run(clouds, settings):
                pass
        except (InputError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return self._finish(context, clouds, settings)

    def invoke(self, context, event):
        """Interactively: run step by step from a timer, with progress, and Esc to cancel."""
        if bpy.app.background or context.window is None:
            return self.execute(context)
        self._settings = self.snapshot()
        try:
            self._clouds_pending = self._clouds(context, self._settings)
            for cloud in self._clouds_pending:  # check the settings before the first timer tick
                make_smoother(cloud, self._settings)
        except (InputError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return self.start_modal(context, run(self._clouds_pending, self._settings))

    def modal_finish(self, context):
        return self._finish(context, self._clouds_pending, self._settings)


classes = (OBJECT_OT_hc_smooth_points,)
