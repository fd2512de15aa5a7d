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
from .properties import alpha_label, annotations, draw_fixed_group, draw_influence_group, uses_alpha, uses_beta

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
    """Set an HC Smooth modifier's inputs from settings as the mesh operators take them."""
    inputs.set_input(modifier, "Method", hc_group.METHOD_NAMES[settings.method])
    inputs.set_input(modifier, "Alpha", settings.alpha)
    inputs.set_input(modifier, "Beta", settings.beta)
    inputs.set_input(modifier, "Iterations", settings.iterations)
    inputs.set_input_attribute(modifier, "Fixed Group", settings.vertex_group)
    # The operators ignore Invert without a group; the modifier would fix everything (weight 0 everywhere).
    inputs.set_input(modifier, "Invert Fixed Group", bool(settings.vertex_group) and settings.invert_vertex_group)
    inputs.set_input(modifier, "Pin Boundary", settings.pin_boundary)
    inputs.set_input_attribute(modifier, "Influence", settings.influence_group)
    # Likewise: without a group the operators smooth fully; the inverted value would keep every vertex still.
    inputs.set_input(modifier, "Invert Influence", bool(settings.influence_group) and settings.invert_influence_group)


def modifier_differences(settings):
    """Why a smoothing with these mesh settings is not what the modifier gives: short lines, none if it is."""
    lines = []
    if settings.method == "HC" and getattr(settings, "auto_amount", False):
        lines.append("The modifier takes Alpha and Iterations as set")
    if getattr(settings, "mode", "SIMULTANEOUS") != "SIMULTANEOUS":
        lines.append("The modifier runs Simultaneous mode")
    if getattr(settings, "tolerance", 0.0) > 0.0:
        lines.append("The modifier runs every iteration")
    return lines


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
        layout.prop(self, "method")
        column = layout.column()
        column.active = uses_alpha(self.method)
        column.prop(self, "alpha", text=alpha_label(self.method))
        row = layout.row()
        row.active = uses_beta(self.method)
        row.prop(self, "beta")
        layout.prop(self, "iterations")
        draw_fixed_group(layout, self, context.active_object)
        layout.prop(self, "pin_boundary")
        draw_influence_group(layout, self, context.active_object)
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
