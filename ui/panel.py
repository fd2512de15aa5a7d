"""The N-panel (3D Viewport sidebar, tab "HC Smooth") and the menu entries beside Blender's smoothing.

Every button passes the scene settings to the operator it calls, so a run from the panel, a menu or
F3 does what the panel shows, and F9 (redo) starts from those values.
"""

import bpy

from .. import settings_spec
from ..operators.draw import draw_mesh_convergence, draw_settings, modifier_differences
from . import fixed, texts
from .preset import HC_SMOOTH_MT_presets
from .settings import MODIFIER_SETTINGS

OBJECT_OPERATOR = "object.hc_smooth"
EDIT_OPERATOR = "mesh.hc_smooth"
POINTS_OPERATOR = "object.hc_smooth_points"
MODIFIER_OPERATOR = "object.hc_smooth_modifier_add"


def smooth_button(layout, context, text=None, icon="MOD_SMOOTH"):
    """The operator button for the current mode, carrying the scene settings; None outside Object/Edit mode."""
    if context.mode == "EDIT_MESH":
        idname, label = EDIT_OPERATOR, "Smooth Selected Vertices"
    elif context.mode == "OBJECT":
        idname, label = OBJECT_OPERATOR, "Smooth Selected Objects"
    else:
        return None
    properties = layout.operator(idname, text=text or label, icon=icon)
    context.scene.hc_smooth.copy_to(properties)
    return properties


def modifier_button(layout, context, text="Add as Modifier", icon="MODIFIER", notes=True):
    """object.hc_smooth_modifier_add with the scene settings (and, with ``notes``, what the modifier does
    differently from the settings)."""
    settings = context.scene.hc_smooth
    for line in modifier_differences(settings) if notes else ():
        layout.label(text=line, icon="INFO")
    properties = layout.operator(MODIFIER_OPERATOR, text=text, icon=icon)
    settings.copy_to(properties, MODIFIER_SETTINGS)
    return properties


class VIEW3D_PT_hc_smooth(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "HC Smooth"
    bl_label = "HC Smooth"

    @classmethod
    def poll(cls, context):
        return context.mode in {"OBJECT", "EDIT_MESH"}

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hc_smooth

        row = layout.row(align=True)
        row.menu(HC_SMOOTH_MT_presets.__name__, text=HC_SMOOTH_MT_presets.bl_label, icon="PRESET")
        row.operator("hc_smooth.preset_add", text="", icon="ADD")
        row.operator("hc_smooth.preset_add", text="", icon="REMOVE").remove_active = True

        layout.use_property_split = True
        layout.use_property_decorate = False
        draw_settings(layout.column(), settings, settings_spec.MESH, shown=settings_spec.MESH_SMOOTHING)
        draw_mesh_convergence(layout.box(), settings, always=True)
        draw_settings(layout.column(), settings, settings_spec.MESH, shown=settings_spec.MESH_RESULT)
        layout.use_property_split = False
        smooth_button(layout.column(), context)
        if context.mode == "OBJECT":
            modifier_button(layout.column(align=True), context)
            layout.operator(POINTS_OPERATOR, text="Smooth Point Cloud", icon="OUTLINER_DATA_POINTCLOUD")


class VIEW3D_PT_hc_smooth_fixed(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "HC Smooth"
    bl_label = "Fixed Vertices"
    bl_parent_id = "VIEW3D_PT_hc_smooth"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hc_smooth
        obj = context.active_object
        mesh_object = obj if obj is not None and obj.type == "MESH" else None

        draw_settings(layout, settings, settings_spec.MESH, mesh_object, shown=settings_spec.MESH_VERTICES)

        column = layout.column(align=True)
        edit_mode = context.mode == "EDIT_MESH"
        for rule in texts.fixed_rules(
            edit_mode=edit_mode,
            vertex_group=settings.vertex_group,
            invert_vertex_group=settings.invert_vertex_group,
            pin_boundary=settings.pin_boundary,
        ):
            column.label(text=rule, icon="PINNED")
        if edit_mode:
            more_rules = bool(settings.vertex_group) or settings.pin_boundary
            draw_edit_count(layout, context, more_rules)
        elif mesh_object is not None:
            draw_object_count(layout, mesh_object, settings)


def draw_edit_count(layout, context, more_rules):
    objects = [obj for obj in context.objects_in_mode_unique_data if obj.type == "MESH"]
    selected, total = fixed.edit_mode_selection(objects)
    layout.label(text=texts.edit_count_line(selected, total, more_rules), icon="INFO")


def draw_object_count(layout, obj, settings):
    result = fixed.cached(obj, settings)
    if result is None and fixed.should_count_now(obj):
        result = fixed.count(obj, settings)
    if result is None:
        layout.operator("hc_smooth.count_fixed", icon="INFO")
    elif isinstance(result, str):
        layout.label(text=result, icon="ERROR")
    else:
        layout.label(text=texts.count_line(*result), icon="INFO")


def draw_edit_menu_entry(self, context):
    """Edit mode, Vertex menu: beside Smooth Vertices and Smooth Vertices (Laplacian)."""
    self.layout.separator()
    smooth_button(self.layout, context, text="HC Smooth Vertices")


def draw_object_menu_entry(self, context):
    self.layout.separator()
    smooth_button(self.layout, context, text="HC Smooth")


def draw_modifier_menu_entry(self, context):
    """Add Modifier > Deform (Properties editor): the HC Smooth modifier with the scene settings."""
    modifier_button(self.layout, context, text="HC Smooth", icon="MOD_SMOOTH", notes=False)


MENU_ENTRIES = (
    (bpy.types.VIEW3D_MT_edit_mesh_vertices, draw_edit_menu_entry),
    (bpy.types.VIEW3D_MT_object, draw_object_menu_entry),
    (bpy.types.OBJECT_MT_modifier_add_deform, draw_modifier_menu_entry),
)

classes = (VIEW3D_PT_hc_smooth, VIEW3D_PT_hc_smooth_fixed)


def register():
    for menu, entry in MENU_ENTRIES:
        menu.append(entry)


def unregister():
    for menu, entry in MENU_ENTRIES:
        menu.remove(entry)
