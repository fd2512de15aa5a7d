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
from ..ui.draw import draw_settings, modifier_differences
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


def draw_add_as_modifier(layout, smoothing):
    """In object.hc_smooth's redo panel: replace the smoothing just made by the modifier, same settings."""
    layout.separator()
    column = layout.column(align=True)
    for line in modifier_differences(smoothing):
        column.label(text=line, icon="INFO")
    button = column.operator(
        OBJECT_OT_hc_smooth_modifier_add.bl_idname, text="Add as Modifier Instead", icon="MODIFIER"
    )
    copy_settings(smoothing, button)
    button.replace_smoothing = True


def undo_last_smoothing(context):
    """Ctrl+Z the smoothing just made, if the last operator was object.hc_smooth; True if it did."""
    operators = context.window_manager.operators
    if not operators or operators[-1].bl_idname != SMOOTH_OPERATOR or not bpy.ops.ed.undo.poll():
        return False
    return bpy.ops.ed.undo() == {"FINISHED"}


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
        if self.replace_smoothing:
            self.replace_smoothing = False  # a redo of this operator must not undo anything again
            if not undo_last_smoothing(context):
                self.report({"WARNING"}, "The last operation was not HC Smooth: nothing was undone")
        objects = [obj for obj in _targets(context) if obj.type == "MESH"]
        if not objects:
            self.report({"ERROR"}, "Select at least one mesh object")
            return {"CANCELLED"}
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


def _targets(context):
    """The selected objects; the active one if none is selected (as Add Modifier treats the active object)."""
    selected = list(context.selected_objects)
    if not selected and context.active_object is not None:
        return [context.active_object]
    return selected


classes = (OBJECT_OT_hc_smooth_modifier_add,)
