"""What the Fixed Vertices panel says, as plain functions of the settings (no bpy: testable on their own).

Each function returns short lines for a narrow sidebar; the panel only picks icons and draws them. The
convergence lines, which the operators' redo panels show as well, come from core/convergence.py (operators/draw.py).
"""


def fixed_rules(*, edit_mode, vertex_group, invert_vertex_group, pin_boundary):
    """The rules that fix vertices, one line each, in the operator's terms."""
    rules = []
    if edit_mode:
        rules.append("Unselected and hidden vertices")
    if vertex_group:
        if invert_vertex_group:
            rules.append(f"Vertices outside group \u201c{vertex_group}\u201d")
        else:
            rules.append(f"Vertices in group \u201c{vertex_group}\u201d")
    if pin_boundary:
        rules.append("Open-boundary vertices")
    return rules


def count_line(n_fixed, n_vertices):
    """'Fixed: 1,204 of 5,994 vertices' (or 'Fixed: none of ...')."""
    if n_fixed == 0:
        return f"Fixed: none of {n_vertices:,} vertices"
    return f"Fixed: {n_fixed:,} of {n_vertices:,} vertices"


def edit_count_line(selected, total, more_rules):
    """Edit mode: unselected and hidden vertices are fixed; group or boundary rules may fix more."""
    if selected == 0:
        return "Nothing selected: nothing will move"
    prefix = "at least " if more_rules else ""
    return f"Fixed: {prefix}{total - selected:,} of {total:,} vertices"
