"""The mesh operators: object.hc_smooth (Object mode) and mesh.hc_smooth (Edit mode).

Thin: read every mesh into a Job (jobs.py), run the core, write back. execute() depends only on the
operator's properties and the mesh, so the redo panel (F9) can re-run it; invoke() runs long work as
a modal timer with progress in the status bar and Esc to cancel (nothing is written until the end).
"""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from .. import core
from . import jobs as jobs_module
from . import mesh_io
from .objects import InputError, unique_data
from .modal_progress import ModalProgress

METHOD_ITEMS = [
    ("HC", "HC", "Laplacian steps pushed back towards the previous and original points: removes noise "
     "without shrinking (Vollmer, Mencl, Müller 1999, section 4)"),
    ("LAPLACIAN", "Laplacian", "Every vertex moves to the average of its neighbours; shrinks (section 3.1)"),
    ("LAPLACIAN_CENTRAL", "Laplacian, Central Point", "Keeps Alpha of the current position (section 3.2)"),
    ("LAPLACIAN_ORIGINAL", "Laplacian, Original Point", "Keeps Alpha of the original position; always converges "
     "(section 3.3)"),
]
MODE_ITEMS = [
    ("SIMULTANEOUS", "Simultaneous", "Every vertex is averaged from the positions before the iteration "
     "(the paper's Algorithm 1)"),
    ("SEQUENTIAL", "Sequential", "Vertices in index order, each using its already-moved neighbours "
     "(Gauss–Seidel)"),
]
OUTPUT_ITEMS = [
    ("MESH", "Mesh", "Move the vertices (of the active shape key, if the mesh has shape keys)"),
    ("SHAPE_KEY", "New Shape Key", "Store the result in a new shape key and leave the mesh as it was"),
]

# Above this many vertex-iterations, an interactive run becomes modal (progress, Esc cancels).
MODAL_WORK = 5_000_000


class SmoothProperties:
    """The operator settings, shared by both operators (and mirrored by the scene settings in ui/)."""

    method: EnumProperty(name="Method", items=METHOD_ITEMS, default="HC")
    alpha: FloatProperty(
        name="Alpha", default=0.1, min=0.0, max=1.0,
        description="HC and Laplacian (original point): pull towards the original positions. "
                    "Laplacian (central point): weight of the current position")
    beta: FloatProperty(
        name="Beta", default=0.6, min=0.0, max=1.0,
        description="HC: weight of a vertex's own difference against its neighbours' (converges above 0.5)")
    iterations: IntProperty(name="Iterations", default=10, min=0, soft_max=200,
                            description="Number of smoothing iterations")
    mode: EnumProperty(name="Mode", items=MODE_ITEMS, default="SIMULTANEOUS")
    tolerance: FloatProperty(
        name="Tolerance", default=0.0, min=0.0, soft_max=0.01, precision=6,
        description="Stop early once no vertex moves more than this fraction of the bounding-box "
                    "diagonal in an iteration (0: always run every iteration)")
    vertex_group: StringProperty(name="Vertex Group",
                                 description="Vertices in this group (weight above 0) stay fixed")
    invert_vertex_group: BoolProperty(name="Invert", description="Fix every vertex outside the group instead: "
                                      "smooth only the group")
    pin_boundary: BoolProperty(name="Pin Boundary", description="Keep open-boundary vertices fixed")
    output: EnumProperty(name="Output", items=OUTPUT_ITEMS, default="MESH")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "method")
        column = layout.column()
        column.active = self.method != "LAPLACIAN"
        column.prop(self, "alpha")
        row = layout.row()
        row.active = self.method == "HC"
        row.prop(self, "beta")
        layout.prop(self, "iterations")
        layout.prop(self, "mode")
        layout.prop(self, "tolerance")
        draw_fixed_group(layout, self, context.active_object)
        layout.prop(self, "pin_boundary")
        layout.prop(self, "output")
        if self.method == "HC":
            draw_convergence_warning(layout, self.alpha, self.beta)


def draw_fixed_group(layout, props, obj):
    """The fixed vertex group field (searchable on a mesh) with its Invert toggle, for the redo panels."""
    row = layout.row(align=True)
    if obj is not None and obj.type == "MESH":
        row.prop_search(props, "vertex_group", obj, "vertex_groups", text="Fixed Group")
    else:
        row.prop(props, "vertex_group", text="Fixed Group")
    row.prop(props, "invert_vertex_group", text="", icon="ARROW_LEFTRIGHT")


def draw_convergence_warning(layout, alpha, beta):
    if not core.in_convergence_region(alpha, beta):
        layout.label(text="Outside the convergence region (Alpha > 0, Beta > 0.5)", icon="ERROR")


class _SmoothOperator(SmoothProperties, ModalProgress):
    """What the two operators share: prepare jobs, run (synchronously or modal), write, report."""

    bl_options = {"REGISTER", "UNDO"}

    def prepare(self, context):
        raise NotImplementedError

    def finish(self, context, jobs):
        """Write every result (the subclasses wrap this with what their mode needs)."""
        for job in jobs:
            jobs_module.write(job, self)

    def _report_done(self, jobs):
        self.report({"INFO"}, jobs_module.summary(jobs, self))
        if self.method == "HC":
            message = core.convergence_message(self.alpha, self.beta)
            if message:
                self.report({"WARNING"}, message)

    def execute(self, context):
        try:
            jobs = self.prepare(context)
            for _ in jobs_module.run(jobs, self):
                pass
        except (InputError, ValueError) as error:  # bad input, or a run that blew up: nothing written
            self.abandon(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        except Exception:  # a bug: back to the mode the user was in, then Blender shows the traceback
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
        try:
            self._jobs = self.prepare(context)
        except InputError as error:
            self.abandon(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        work = sum(len(job.positions) for job in self._jobs) * self.iterations
        if work < MODAL_WORK:
            return self._finish_now(context)
        chunk = max(1, int(MODAL_WORK // max(1, work // max(1, self.iterations))))
        return self.start_modal(context, jobs_module.run(self._jobs, self, chunk=chunk))

    def _finish_now(self, context):
        try:
            for _ in jobs_module.run(self._jobs, self):
                pass
        except ValueError as error:
            self.abandon(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        except Exception:
            self.abandon(context)
            raise
        return self.modal_finish(context)

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
        return [jobs_module.make_job(obj, self) for obj in unique_data(objects, first=context.active_object)]


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
            jobs.append(jobs_module.make_job(obj, self, extra_fixed=~selected | hidden))
        if not jobs:
            raise InputError("Select some visible vertices to smooth")
        return jobs

    def finish(self, context, jobs):
        try:
            super().finish(context, jobs)
        finally:
            bpy.ops.object.mode_set(mode="EDIT")

    def abandon(self, context):
        if context.mode != "EDIT_MESH":
            bpy.ops.object.mode_set(mode="EDIT")


classes = (OBJECT_OT_hc_smooth, MESH_OT_hc_smooth)
