"""object.hc_smooth_points: smooth point clouds (meshes of loose vertices, PointCloud objects) through
their RFS mesh (paper section 7, core.smooth_point_cloud).

Thin like the mesh operators: read every selected cloud, validate, smooth, and only then write, so a
failure leaves everything as it was. execute() depends only on the properties and the objects, so the
redo panel (F9) can re-run it. The steps are plain functions of a ``PointSettings`` (read_clouds, run,
write, messages) that the operator and the command line (cli/command.py) both call.
"""

import warnings

import bpy
import numpy as np

from .. import core, settings_spec
from ..core import MAX_POINT_CLOUD_STEPS, PointCloudSmoother, collinear, matched_alpha, reach_gap_problem
from ..settings_spec import PointSettings
from . import mesh_io, objects
from .draw import draw_convergence, draw_settings
from .modal_progress import ModalProgress
from .objects import InputError, unique_data
from .properties import annotations, set_by_caller

POINT_TYPES = ("MESH", "POINTCLOUD")
# Reach and Gap as the panel names them, for the rule that ties them.
REACH_GAP = (settings_spec.SPACING_FACTOR.label, settings_spec.GAP_FACTOR.label)


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


def _too_few_points(name, positions):
    """Why ``positions`` cannot be smoothed (fewer than three distinct points, or all on one line: no RFS
    face), or None."""
    n = len(positions)
    if n == 1:
        return f"'{name}' is a single point: nothing to smooth"
    differs = np.any(positions != positions[0], axis=1)
    if not differs.any():
        return f"All {n} points of '{name}' coincide: nothing to smooth"
    other = np.all(positions == positions[int(np.argmax(differs))], axis=1)
    if np.all(other | ~differs):  # every point is the first one or that other one
        return f"The {n} points of '{name}' lie at only 2 distinct positions: nothing to smooth"
    if collinear(positions):
        return f"The {n} points of '{name}' lie on one straight line: no RFS face can form, nothing to smooth"
    return None


class Cloud:
    """One object to smooth: where its points come from and go to."""

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
        too_few = _too_few_points(obj.data.name, positions)
        if too_few:
            raise InputError(too_few)
        self.positions = positions
        self.fixed = self._fixed(settings)
        self.result = None
        self.report = None

    @classmethod
    def of_arrays(cls, name, positions, fixed=None):
        """A cloud given as arrays (a file's points, on the command line), checked as an object's is;
        ``name`` is what messages call it. It has no object to write to."""
        if len(positions) == 0:
            raise InputError(f"'{name}' has no points: nothing to smooth")
        too_few = _too_few_points(name, positions)
        if too_few:
            raise InputError(too_few)
        cloud = cls.__new__(cls)
        cloud.obj = cloud.data = cloud.key_block = None
        cloud.positions, cloud.fixed, cloud.result, cloud.report = positions, fixed, None, None
        return cloud

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


def check_settings(settings):
    """Raise InputError for settings no cloud can run with (Reach and Gap that do not fit together)."""
    problem = reach_gap_problem(settings.spacing_factor, settings.gap_factor, REACH_GAP)
    if problem:
        raise InputError(problem)


def read_clouds(selected, settings):
    """Read and check every object (an object data shared by several objects once); raises InputError. Reads only."""
    check_settings(settings)
    return [Cloud(obj, settings) for obj in unique_data(selected)]


def make_smoother(cloud, settings):
    """The core's stepwise run for one cloud; raises ValueError for settings the core refuses."""
    return PointCloudSmoother(
        cloud.positions,
        alpha="auto" if settings.auto_amount else settings.alpha,
        beta=settings.beta,
        rounds=settings.rounds,
        iterations_per_round="auto" if settings.auto_amount else settings.iterations_per_round,
        fixed=cloud.fixed,
        neighbours=settings.neighbours,
        spacing_factor=settings.spacing_factor,
        gap_factor=settings.gap_factor,
        min_quality=settings.min_quality,
        swap=settings.swap,
    )


def run(clouds, settings):
    """Every cloud's stages in turn; yields the fraction done and sets each cloud's result. Writes nothing."""
    for number, cloud in enumerate(clouds):
        smoother = make_smoother(cloud, settings)
        with warnings.catch_warnings():  # the convergence region is reported once, at the end
            warnings.simplefilter("ignore", core.ConvergenceWarning)
            for fraction in smoother.steps():
                yield (number + fraction) / len(clouds)
        cloud.result, cloud.report = smoother.result, smoother.report


def write(clouds, settings, context):
    """Write every result (and the RFS meshes if asked for); call only once ``run`` has finished."""
    for cloud in clouds:
        cloud.write()
        if settings.keep_rfs_mesh:
            cloud.add_rfs_object(context)


def lowest_alpha(settings, given=()):
    """The smallest alpha a run with these settings (``given``: the names the caller set) can use, before it
    has estimated the noise."""
    # With the automatic amount, alpha is matched_alpha(steps) >= matched_alpha(MAX_POINT_CLOUD_STEPS) > 0:
    # only beta can leave the region.
    automatic = settings_spec.automatic(settings_spec.values_of(settings, settings_spec.POINTS), given)
    return matched_alpha(MAX_POINT_CLOUD_STEPS) if automatic else settings.alpha


def convergence_note(settings):
    """The convergence-region warning for these settings (before a run), or None."""
    return core.convergence_message(lowest_alpha(settings), settings.beta)


def amount(report):
    """What ran: '3 rounds of 15 steps'."""
    return f"{report.rounds} rounds of {report.iterations_per_round} steps"


def stuck_warning(clouds):
    """The warning for runs where most points found no RFS face (and so could not move), or None."""
    still = sum(c.report.isolated for c in clouds)
    distinct = sum(c.report.n_distinct for c in clouds)
    if still <= distinct / 2:
        return None
    counted = "points" if distinct == sum(len(c.positions) for c in clouds) else "distinct points"
    # Typically scan lines much farther apart than the points along them: the graph keeps to the
    # lines and no faces form, so the points cannot move.
    return (
        f"{still} of {distinct} {counted} have no RFS faces and did not move: the points are much farther "
        "apart in one direction (scan lines?). Raise Reach, Gap and Neighbours to connect them"
    )


def summary(clouds, settings):
    points = sum(len(c.positions) for c in clouds)
    seconds = sum(sum(c.report.seconds.values()) for c in clouds)
    still = sum(c.report.isolated for c in clouds)
    names = f"{len(clouds)} objects" if len(clouds) > 1 else f"'{clouds[0].obj.name}'"  # what the user selected

    def described(report):
        automatic = report.noise is not None and settings.auto_amount
        noise = f"noise {report.noise.ratio:.2f}x spacing: " if automatic else ""
        return f"{noise}{amount(report)}, alpha {report.alpha:.3g}"

    moved = "; ".join(  # the words of the mesh operators' reports (core.Change.summary)
        core.measure_change(c.positions, c.result).summary().replace("vertices", "points").replace("vertex", "point")
        for c in clouds
    )
    return (
        f"HC Smooth Points on {names}: {points} points, "
        + "; ".join(described(c.report) for c in clouds)
        + f", {seconds:.2f} s"
        + (f", {still} points without RFS faces stayed put" if still else "")
        + f"; {moved}"
    )


def messages(clouds, settings):
    """[(level, text)] to report after a finished run: the summary, then any warnings."""
    found = [("INFO", summary(clouds, settings))]
    for level, text in (
        ("WARNING", stuck_warning(clouds)),
        ("WARNING", core.convergence_message(min(c.report.alpha for c in clouds), settings.beta)),
    ):
        if text:
            found.append((level, text))
    return found


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
