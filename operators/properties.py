"""Blender's side of settings_spec: the properties built from the declarations, and what the operators'
redo panels (F9) and the N-panel (ui/panel.py) draw alike.

The operators and the scene settings (ui/settings.py) take their ``__annotations__`` from
``annotations()``, so both are the same declaration turned into bpy.props.
"""

from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from .. import core

PROPERTY = {
    "enum": EnumProperty,
    "float": FloatProperty,
    "int": IntProperty,
    "bool": BoolProperty,
    "string": StringProperty,
}
LIMITS = ("min", "max", "soft_max", "step", "precision")


def bpy_property(setting):
    """A settings_spec.Setting as a bpy.props property."""
    options = {"name": setting.label, "description": setting.description, "default": setting.default}
    options.update((key, getattr(setting, key)) for key in LIMITS if getattr(setting, key) is not None)
    if setting.kind == "enum":
        options["items"] = [(choice.identifier, choice.label, choice.description) for choice in setting.items]
    return PROPERTY[setting.kind](**options)


def annotations(settings):
    """{identifier: property} for a class body's ``__annotations__`` (Blender registers those)."""
    return {setting.name: bpy_property(setting) for setting in settings}


def uses_alpha(method):
    """Plain Laplacian has no alpha; every other method weights something by it."""
    return method != "LAPLACIAN"


def uses_beta(method):
    return method == "HC"


def alpha_label(method):
    if method == "LAPLACIAN_CENTRAL":
        return "Alpha (keep current)"
    return "Alpha (pull to original)"


def convergence_status(method, alpha, beta):
    """(converges, lines): whether the method settles on a shape that keeps its size, and why, in short
    lines for a narrow panel (the full sentence for reports is core.convergence_message).

    HC: Theorem 5.2 (alpha > 0, beta > 0.5). The Laplacian variants (section 5): plain and central
    shrink towards a point as iterations grow; with the original point and alpha > 0 they converge,
    but to a shrunken compromise (section 3.3).
    """
    if method == "HC":
        if core.in_convergence_region(alpha, beta):
            return True, ["Converges: \u03b1 > 0 and \u03b2 > 0.5", "(paper, Theorem 5.2)"]
        lines = ["Outside the convergence region:"]
        if not alpha > 0.0:
            lines.append("\u03b1 = 0: no pull to the original")
        if not beta > 0.5:
            lines.append(f"\u03b2 = {beta:.3g} is not above 0.5")
        lines.append("many iterations may drift")
        return False, lines
    if method == "LAPLACIAN_ORIGINAL" and alpha > 0.0:
        return True, ["Converges (\u03b1 > 0), but shrinks", "part of the way (paper 3.3)"]
    return False, ["Shrinks with every iteration", "(no limit but a point, paper 3.1)"]


def draw_convergence(layout, method, alpha, beta, always=False):
    """The convergence_status lines under a check mark or a warning sign; only a warning unless ``always``."""
    converges, lines = convergence_status(method, alpha, beta)
    if converges and not always:
        return
    column = layout.column(align=True)
    for index, line in enumerate(lines):
        icon = ("CHECKMARK" if converges else "ERROR") if index == 0 else "BLANK1"
        column.label(text=line, icon=icon)


def draw_group_field(layout, props, obj, name, invert, text):
    """A vertex-group name field (searchable on a mesh) with its Invert toggle, greyed out while the
    name is empty; for the redo panels and the N-panel."""
    row = layout.row(align=True)
    if obj is not None and obj.type == "MESH":
        row.prop_search(props, name, obj, "vertex_groups", text=text)
    else:
        row.prop(props, name, text=text)
    sub = row.row(align=True)
    sub.active = bool(getattr(props, name))
    sub.prop(props, invert, text="", icon="ARROW_LEFTRIGHT")


def draw_fixed_group(layout, props, obj, text="Fixed Group"):
    """The group of vertices that stay fixed."""
    draw_group_field(layout, props, obj, "vertex_group", "invert_vertex_group", text)


def draw_influence_group(layout, props, obj, text="Influence"):
    """The painted influence: a vertex group whose weights scale each vertex's move."""
    draw_group_field(layout, props, obj, "influence_group", "invert_influence_group", text)
