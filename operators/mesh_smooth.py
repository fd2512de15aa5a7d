"""The mesh operators: object.hc_smooth (Object mode) and mesh.hc_smooth (Edit mode).

Thin: read every mesh into a Job (mesh_objects.py), run it (jobs.mesh), write back. execute() depends only
on the operator's properties and the mesh, so the redo panel (F9) can re-run it; invoke() runs long work as
a modal timer with progress in the status bar and Esc to cancel (nothing is written until the end).
"""

import bpy

from .. import core, settings_spec
from ..jobs import mesh as mesh_jobs
from . import mesh_io, mesh_objects
from .draw import draw_mesh_convergence, draw_settings
from .modal_progress import ModalProgress
from .modifier import draw_add_as_modifier
from .objects import InputError, unique_data
from .properties import annotations, set_by_caller

# Above this many vertex-iterations, an interactive run becomes modal (progress, Esc cancels).
MODAL_WORK = 5_000_000


class SmoothProperties:
    """The operator settings (settings_spec.MESH), shared by both operators; the scene settings in ui/ are
    built from the same declarations."""

    __annotations__ = annotations(settings_spec.MESH)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        given = set_by_caller(self, settings_spec.CHOSEN)  # Alpha or Iterations set: every number as set
        draw_settings(layout, self, settings_spec.MESH, context.active_object, given=given)
        draw_mesh_convergence(layout, self, given=given)
        # Object mode only: Edit mode's selection (the vertices to smooth) has no equivalent in a modifier.
        if self.bl_idname == OBJECT_OT_hc_smooth.bl_idname:
            draw_add_as_modifier(layout, self, given)


class _SmoothOperator(SmoothProperties, ModalProgress):
    """What the two operators share: prepare jobs, run (synchronously or modal), write, report."""

    bl_options = {"REGISTER", "UNDO"}

    def prepare(self, context):
        raise NotImplementedError

    def finish(self, context, jobs):
        """Write every result (the subclasses wrap this with what their mode needs)."""
        mesh_objects.write_all(jobs, self._settings)
        if self._settings.deviation_map and any(job.map_names.shown for job in jobs):
            show_attribute_colors(context)  # a map made the active colours: show them

    def _report_done(self, jobs):
        self.report({"INFO"}, mesh_jobs.summary(jobs, self._settings, scene_length(bpy.context.scene)))
        message = mesh_jobs.convergence_warning(jobs)
        if message:
            self.report({"WARNING"}, message)

    def _given(self):
        """The numbers the caller set (used as given)."""
        return set_by_caller(self, settings_spec.CHOSEN)

    def _run(self, jobs, chunk=None):
        """The run's generator, on the settings' snapshot and with the numbers the caller set."""
        return mesh_jobs.run(jobs, self._settings, chunk=chunk, given=self._given())

    def execute(self, context):
        self._settings = settings_spec.MeshSettings.of(self)  # what prepare, run, write and report read
        return self._run_now(context)

    def _run_now(self, context, jobs=None):
        """Prepare (unless ``jobs`` are), smooth every job in one go, write and report. On any error
        nothing is written and the mode is restored; bugs go on to Blender with their traceback."""
        try:
            jobs = self.prepare(context) if jobs is None else jobs
            for _ in self._run(jobs):
                pass
        except (InputError, ValueError) as error:  # bad input, or a run that blew up
            self.abandon(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        except Exception:
            self.abandon(context)
            raise
        self.finish(context, jobs)
        self._report_done(jobs)
        return {"FINISHED"}

    def abandon(self, context):
        """Undo whatever prepare() changed (mode switches); nothing was written."""

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        self._settings = settings_spec.MeshSettings.of(self)  # a modal run must not see later edits
        try:
            self._jobs = self.prepare(context)
        except (InputError, ValueError) as error:
            self.abandon(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        vertices = sum(len(job.positions) for job in self._jobs)
        automatic = settings_spec.automatic(settings_spec.values_of(self._settings, settings_spec.MESH), self._given())
        iterations = core.MAX_ITERATIONS if automatic else self.iterations
        if vertices * iterations < MODAL_WORK:
            return self._run_now(context, self._jobs)
        return self.start_modal(context, self._run(self._jobs, chunk=max(1, MODAL_WORK // max(1, vertices))))

    def modal_finish(self, context):
        self.finish(context, self._jobs)
        self._report_done(self._jobs)
        return {"FINISHED"}

    def modal_abandon(self, context):
        self.abandon(context)


class OBJECT_OT_hc_smooth(_SmoothOperator, bpy.types.Operator):
    """Smooth the selected mesh objects without shrinking them (HC algorithm)"""

    bl_idname = "object.hc_smooth"
    bl_label = "HC Smooth"

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def prepare(self, context):
        objects = [obj for obj in context.selected_objects if obj.type == "MESH"]
        if not objects:
            others = ", ".join(sorted({obj.type.lower() for obj in context.selected_objects}))
            raise InputError("Select at least one mesh object" + (f" (selected: {others})" if others else ""))
        return [mesh_objects.make_job(obj, self._settings) for obj in unique_data(objects, first=context.active_object)]


class MESH_OT_hc_smooth(_SmoothOperator, bpy.types.Operator):
    """Smooth the selected vertices without shrinking the mesh (HC algorithm); unselected and hidden vertices stay"""

    bl_idname = "mesh.hc_smooth"
    bl_label = "HC Smooth Vertices"

    @classmethod
    def poll(cls, context):
        return context.mode == "EDIT_MESH"

    def prepare(self, context):
        # Edit-mode data lives in BMesh and the mesh arrays are stale until it is written back. Leaving
        # Edit mode writes it once for all objects in the mode and opens the fast bulk paths; finish()
        # and abandon() come back.
        objects = list(context.objects_in_mode_unique_data)
        bpy.ops.object.mode_set(mode="OBJECT")
        jobs = []
        for obj in objects:
            mesh = obj.data
            selected = mesh_io.read_bool_attribute(mesh, ".select_vert")
            hidden = mesh_io.read_bool_attribute(mesh, ".hide_vert")
            if not (selected & ~hidden).any():
                continue
            jobs.append(mesh_objects.make_job(obj, self._settings, extra_fixed=~selected | hidden))
        if not jobs:
            raise InputError("Select some visible vertices to smooth")
        return jobs

    def finish(self, context, jobs):
        try:
            super().finish(context, jobs)
            for job in jobs:
                mesh_jobs.release(job)
        finally:
            bpy.ops.object.mode_set(mode="EDIT")

    def abandon(self, context):
        if context.mode != "EDIT_MESH":
            bpy.ops.object.mode_set(mode="EDIT")


def show_attribute_colors(context):
    """Solid shading shows the active colour attribute in every 3D Viewport of the screen (none without one:
    a script run without a window). Not part of the undo history, like any view setting."""
    screen = getattr(context, "screen", None)
    for area in screen.areas if screen is not None else ():
        for space in area.spaces:
            if space.type == "VIEW_3D":
                space.shading.color_type = "VERTEX"  # shown as "Attribute"


def scene_length(scene):
    """A length formatter in the scene's units ('0.12 mm'), as the legend of a deviation map says it."""
    units = scene.unit_settings if scene is not None else None
    if units is None or units.system == "NONE":
        return None  # core's default: plain numbers

    def length(value):
        return bpy.utils.units.to_string(units.system, "LENGTH", value * units.scale_length, precision=3)

    return length


classes = (OBJECT_OT_hc_smooth, MESH_OT_hc_smooth)
