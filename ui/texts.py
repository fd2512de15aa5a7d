"""What the panel says, as plain functions of the settings (no bpy: testable on their own).

Each function returns short lines for a narrow sidebar; the panel only picks icons and draws them.
"""

from .. import core

# Operator property identifiers shared by the scene settings, the panel buttons and the presets.
METHODS = ("HC", "LAPLACIAN", "LAPLACIAN_CENTRAL", "LAPLACIAN_ORIGINAL")
MODES = ("SIMULTANEOUS", "SEQUENTIAL")
OUTPUTS = ("MESH", "SHAPE_KEY")


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
    """(converges, lines): whether the method settles on a shape that keeps its size, and why.

    HC: Theorem 5.2 (alpha > 0, beta > 0.5). The Laplacian variants (section 5): plain and central
    shrink towards a point as iterations grow; with the original point and alpha > 0 they converge,
    but to a shrunken compromise (section 3.3).
    """
    if method == "HC":
        if core.in_convergence_region(alpha, beta):
            return True, ["Converges: \u03b1 > 0 and \u03b2 > 0.5", "(paper, Theorem 5.2)"]
        lines = ["Outside the proven region:"]
        if not alpha > 0.0:
            lines.append("\u03b1 = 0: no pull to the original")
        if not beta > 0.5:
            lines.append(f"\u03b2 = {beta:.3g} is not above 0.5")
        lines.append("many iterations may drift")
        return False, lines
    if method == "LAPLACIAN_ORIGINAL" and alpha > 0.0:
        return True, ["Converges (\u03b1 > 0), but shrinks", "part of the way (paper 3.3)"]
    return False, ["Shrinks with every iteration", "(no limit but a point, paper 3.1)"]


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
