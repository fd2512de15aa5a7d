"""object.hc_smooth_modifier_add: the HC Smooth modifier on the selected meshes, and the redo panel's
"Add as Modifier" that turns the smoothing just made into that modifier.

An adapter like the other operators: no numerical code. The modifier is a Geometry Nodes modifier
running the group of nodes/hc_group.py (one per file, made on first use); its inputs are set by name
(nodes/inputs.py), so applying it gives what object.hc_smooth gives with the same settings.
"""

import bpy
from bpy.props import BoolProperty

from .. import settings_spec
from ..nodes import hc_group, inputs
from . import mesh_io, undo_steps
from .draw import draw_settings, modifier_differences
from .properties import annotations

MODIFIER_NAME = "HC Smooth"
SMOOTH_OPERATOR = "OBJECT_OT_hc_smooth"  # the smoothing whose redo panel offers Add as Modifier
# What the modifier takes from the mesh settings.
SETTINGS = settings_spec.MODIFIER


def add_modifier(obj, settings):
    """Add the HC Smooth modifier to ``obj`` (at the end of its stack) with ``settings`` (SETTINGS' names: an
    operator's properties, the scene settings or a plain object)."""
    modifier = obj.modifiers.new(MODIFIER_NAME, "NODES")
    modifier.node_group = hc_group.ensure_group()
    configure(modifier, settings)
    return modifier


def configure(modifier, settings):
    """Set an HC Smooth modifier's inputs from settings as the mesh operators take them: each SETTINGS' input
    by its name (hc_group.input_name), a vertex group's name as the group its field input reads."""
    # The operators ignore an Invert without its group. The modifier would not: an inverted empty group fixes
    # every vertex, an inverted empty influence keeps every vertex still. So Invert is on only with a group.
    group_of = {setting.invert: setting.name for setting in SETTINGS if setting.invert}  # Invert -> its group
    for setting in SETTINGS:
        name, value = hc_group.input_name(setting), getattr(settings, setting.name)
        if setting.invert:
            inputs.set_input_attribute(modifier, name, value)
        elif setting.name in group_of:
            inputs.set_input(modifier, name, bool(getattr(settings, group_of[setting.name])) and value)
        elif setting.kind == "enum":  # the Method menu: by its item's name
            inputs.set_input(modifier, name, hc_group.METHOD_NAMES[value])
        else:
            inputs.set_input(modifier, name, value)


def copy_settings(source, properties):
    for setting in SETTINGS:
        setattr(properties, setting.name, getattr(source, setting.name))


def draw_add_as_modifier(layout, smoothing, given=()):
    """In object.hc_smooth's redo panel: replace the smoothing just made by the modifier, same settings.
    ``given``: the names its caller set."""
    layout.separator()
    column = layout.column(align=True)
    for line in modifier_differences(smoothing, given):
        column.label(text=line, icon="INFO")
    button = column.operator(
        OBJECT_OT_hc_smooth_modifier_add.bl_idname, text="Add as Modifier Instead", icon="MODIFIER"
    )
    copy_settings(smoothing, button)
    button.replace_smoothing = True


def undo_last_smoothing(context):
    """Ctrl+Z the smoothing just made: None if it did, else (level, message) saying why not.

    Only the smoothing's own undo step is taken back. The last operator can be object.hc_smooth while another
    undo step came after it (an edited property pushes one, and is no operator): then undoing one step would
    take back that edit and leave the mesh smoothed, so nothing is undone and the caller stops ("ERROR")."""
    operators = context.window_manager.operators
    if not operators or operators[-1].bl_idname != SMOOTH_OPERATOR:
        return "WARNING", "The last operation was not HC Smooth: nothing was undone"
    step = undo_steps.active_step_name(context.window_manager)
    if step is None or not bpy.ops.ed.undo.poll():
        return (
            "ERROR",
            "The undo history could not be read: nothing was changed. Undo the smoothing, then add the modifier",
        )
    if step != operators[-1].bl_label:
        return "ERROR", (
            f"Another change ('{step}') came after HC Smooth, and Ctrl+Z would take that back instead: nothing was "
            "changed. Undo back to before the smoothing, then add the modifier"
        )
    if bpy.ops.ed.undo() != {"FINISHED"}:
        return "ERROR", "The smoothing could not be undone: nothing was changed"
    return None


class OBJECT_OT_hc_smooth_modifier_add(bpy.types.Operator):
    """Add an HC Smooth modifier (Geometry Nodes, simultaneous mode) to the selected mesh objects"""

    bl_idname = "object.hc_smooth_modifier_add"
    bl_label = "Add HC Smooth Modifier"
    bl_options = {"REGISTER", "UNDO"}

    __annotations__ = {
        **annotations(SETTINGS),
        # Set by the smoothing's redo panel: undo that smoothing first, so the mesh is not smoothed twice.
        "replace_smoothing": BoolProperty(name="Replace Smoothing", default=False, options={"HIDDEN", "SKIP_SAVE"}),
    }

    @classmethod
    def poll(cls, context):
        return any(obj.type == "MESH" for obj in _targets(context))

    def execute(self, context):
        objects = [obj for obj in _targets(context) if obj.type == "MESH"]
        if not objects:
            self.report({"ERROR"}, "Select at least one mesh object")
            return {"CANCELLED"}
        unreadable = [problem for obj in objects for problem in shadowed_groups(obj, self)]
        for problem in unreadable:
            self.report({"ERROR"}, problem)
        if unreadable:
            return {"CANCELLED"}
        if self.replace_smoothing:
            self.replace_smoothing = False  # a redo of this operator must not undo anything again
            problem = undo_last_smoothing(context)
            if problem is not None:
                level, message = problem
                self.report({level}, message)
                if level == "ERROR":
                    return {"CANCELLED"}
            objects = [obj for obj in _targets(context) if obj.type == "MESH"]  # undo reloads the objects
        for obj in objects:
            add_modifier(obj, self)
            for warning in missing_groups(obj, self):
                self.report({"WARNING"}, warning)
        names = f"'{objects[0].name}'" if len(objects) == 1 else f"{len(objects)} objects"
        self.report({"INFO"}, f"Added the {MODIFIER_NAME} modifier to {names}")
        return {"FINISHED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        draw_settings(layout, self, SETTINGS, context.active_object)
        layout.label(text="Simultaneous mode", icon="INFO")


def missing_groups(obj, settings):
    """What the modifier does with vertex group names ``obj`` lacks (it reads them as weight 0), as warnings."""
    name = f"Object '{obj.name}' has no vertex group"
    if settings.vertex_group and obj.vertex_groups.get(settings.vertex_group) is None:
        yield f"{name} '{settings.vertex_group}': no vertex is fixed by it"
    if settings.influence_group and obj.vertex_groups.get(settings.influence_group) is None:
        still = "every vertex takes the full step" if settings.invert_influence_group else "no vertex moves"
        yield f"{name} '{settings.influence_group}' (the influence group): {still}"


def shadowed_groups(obj, settings):
    """The vertex groups of ``settings`` that the modifier would not read on ``obj``, as messages: Geometry Nodes
    look a group up by its name, and an attribute of that name comes first (Blender 4.x: built-in ones such as
    "id", "material_index", "sharp_edge" even where the mesh lacks them; every version: the mesh's own, such
    as "position" or a UV map). The operators read such groups correctly; the modifier cannot."""
    if not mesh_io.geometry_nodes_move_vertices(obj):
        yield (
            f"Object '{obj.name}' has a vertex group named 'position', which this Blender's Geometry Nodes write the "
            "positions into: no Geometry Nodes modifier can move its vertices. Rename the vertex group"
        )
    for setting in SETTINGS:
        if setting.kind != "string" or not getattr(settings, setting.name):
            continue
        group = obj.vertex_groups.get(getattr(settings, setting.name))
        if group is not None and not mesh_io.group_read_by_name(obj, group.index):
            yield (
                f"Object '{obj.name}': Geometry Nodes read the attribute '{group.name}', not the vertex group of that "
                f"name ({setting.label}): rename the vertex group to use it in the modifier"
            )


def _targets(context):
    """The selected objects; the active one if none is selected (as Add Modifier treats the active object)."""
    selected = list(context.selected_objects)
    if not selected and context.active_object is not None:
        return [context.active_object]
    return selected


classes = (OBJECT_OT_hc_smooth_modifier_add,)
