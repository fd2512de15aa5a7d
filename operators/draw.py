"""How every panel draws the settings: the operators' redo panels (F9) and the N-panel alike.

``draw_settings`` lays out settings by their declarations (settings_spec): a row each, greyed out where the
setting's ``active`` rule says it does not apply, labelled by its ``text`` rule, a vertex group searchable
on a mesh with its Invert toggle beside it. A new setting is drawn everywhere its tuple is drawn.

Plain drawing on a layout, without bpy: the operators' redo panels and ui/panel.py import it.
"""

from .. import settings_spec
from ..core import convergence_lines
from ..settings_spec import values_of

CORE_METHOD = {choice.identifier: choice.core for choice in settings_spec.METHOD.items}


def draw_settings(layout, props, settings, obj=None, shown=None, given=()):
    """Draw ``shown`` (default: all of ``settings``, the declarations ``props`` holds) in declaration order.
    ``obj``: the object whose vertex groups a group name is picked from (None or not a mesh: a plain field).
    ``given``: the names the caller set (a redo panel's operator), which the ``active`` rules read."""
    values = values_of(props, settings)
    inverts = {setting.invert for setting in settings if setting.invert}
    for setting in settings if shown is None else shown:
        if setting.name in inverts:
            continue  # drawn beside its group
        row = layout.row(align=bool(setting.invert))
        if setting.active is not None:
            row.active = setting.active(values, given)  # greyed, still editable: it applies once the rule holds
        if setting.invert:
            _draw_group(row, props, obj, setting)
        elif setting.text is not None:
            row.prop(props, setting.name, text=setting.text(values))
        else:
            row.prop(props, setting.name)


def _draw_group(row, props, obj, setting):
    """A vertex-group name field (searchable on a mesh) with its Invert toggle, greyed out while the name is
    empty."""
    if obj is not None and obj.type == "MESH":
        row.prop_search(props, setting.name, obj, "vertex_groups")
    else:
        row.prop(props, setting.name)
    sub = row.row(align=True)
    sub.active = bool(getattr(props, setting.name))
    sub.prop(props, setting.invert, text="", icon="ARROW_LEFTRIGHT")


def draw_convergence(layout, method, alpha, beta, always=False):
    """core's convergence lines for ``method`` (settings_spec.METHOD's identifier) under a check mark or a
    warning sign; only a warning unless ``always``."""
    converges, lines = convergence_lines(CORE_METHOD[method], alpha, beta)
    if converges and not always:
        return
    column = layout.column(align=True)
    for index, line in enumerate(lines):
        icon = ("CHECKMARK" if converges else "ERROR") if index == 0 else "BLANK1"
        column.label(text=line, icon=icon)


def draw_mesh_convergence(layout, props, always=False, given=()):
    """The convergence lines of mesh settings. In a redo panel (not ``always``) only HC's warning: the
    Laplacian variants shrink by design. ``given``: the names the caller set."""
    values = values_of(props, settings_spec.MESH)
    if values["keep_sharp_edges"] or (values["method"] != "HC" and not always):
        return  # Keep Sharp Edges is not HC's umbrella step: Theorem 5.2 says nothing about it
    # The automatic amount runs alpha 0 for the few iterations it chooses (no drift): only beta can warn.
    alpha = 1.0 if settings_spec.automatic(values, given) else values["alpha"]
    draw_convergence(layout, values["method"], alpha, values["beta"], always)


def modifier_differences(settings, given=()):
    """Why a smoothing with these mesh settings (``given``: the names the caller set) is not what the modifier
    gives: short lines, none if it is."""
    lines = []
    if settings.keep_sharp_edges:
        lines.append("The modifier has no Keep Sharp Edges: it runs the method")
    if settings_spec.automatic(values_of(settings, settings_spec.MESH), given):
        lines.append("The modifier takes Alpha, Iterations and Deviation Limit as set")
    if settings.iterations > settings_spec.MODIFIER_MAX_ITERATIONS:
        lines.append(f"The modifier runs at most {settings_spec.MODIFIER_MAX_ITERATIONS} iterations")
    if settings.mode != "SIMULTANEOUS":
        lines.append("The modifier runs Simultaneous mode")
    if settings.tolerance > 0.0:
        lines.append("The modifier runs every iteration")
    if settings.deviation_map:
        lines.append("The modifier stores hc_deviation without its colours")
    if settings.keep_outline and not settings.pin_boundary:
        lines.append("The modifier has no Keep Outline: open boundaries are pulled in")
    return lines
