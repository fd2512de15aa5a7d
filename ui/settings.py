"""Scene-level settings (``scene.hc_smooth``) that the panel and menu entries hand to the operators.

The identifiers and enum items are those of the operators' properties (object.hc_smooth,
mesh.hc_smooth), so a button copies them one to one; tests check that the two stay in step.
"""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

# The settings a button passes on (all of them) and those a preset stores: the strength of the smoothing,
# not the choices that belong to one mesh (vertex group, boundary, output).
OPERATOR_SETTINGS = (
    "method", "alpha", "beta", "iterations", "mode", "tolerance",
    "vertex_group", "invert_vertex_group", "pin_boundary", "output",
)
PRESET_SETTINGS = ("method", "alpha", "beta", "iterations", "mode", "tolerance")


class HCSmoothSettings(bpy.types.PropertyGroup):
    method: EnumProperty(
        name="Method",
        description="Smoothing algorithm",
        items=(
            ("HC", "HC", "Laplacian step, then push every vertex back towards its previous and original "
             "position (Vollmer, Mencl, M\u00fcller 1999): removes noise without shrinking"),
            ("LAPLACIAN", "Laplacian", "Move every vertex to the average of its neighbours (paper 3.1); "
             "shrinks with every iteration"),
            ("LAPLACIAN_CENTRAL", "Laplacian, Central Point", "Laplacian that keeps the weight alpha on the "
             "current position (paper 3.2): slower, shrinks the same way"),
            ("LAPLACIAN_ORIGINAL", "Laplacian, Original Point", "Laplacian that pulls towards the original "
             "position with weight alpha (paper 3.3): converges, but shrinks part of the way"),
        ),
        default="HC",
    )
    alpha: FloatProperty(
        name="Alpha",
        description="HC and Laplacian with original point: weight of the original position "
        "(0 = none, higher keeps more of the input, noise included). "
        "Laplacian with central point: weight of the current position",
        min=0.0, max=1.0, default=0.1, step=1, precision=3,
    )
    beta: FloatProperty(
        name="Beta",
        description="HC: weight of a vertex's own correction against its neighbours'. "
        "Convergence is proven for beta > 0.5 (with alpha > 0)",
        min=0.0, max=1.0, default=0.6, step=1, precision=3,
    )
    iterations: IntProperty(
        name="Iterations",
        description="Number of smoothing steps (heavier noise needs more)",
        min=0, soft_max=200, default=10,
    )
    mode: EnumProperty(
        name="Mode",
        description="Order in which vertices are updated within a step",
        items=(
            ("SIMULTANEOUS", "Simultaneous", "Every vertex reads the positions of the previous step "
             "(paper, Algorithm 1)"),
            ("SEQUENTIAL", "Sequential", "Vertices in index order, each reading the already updated "
             "positions of lower-index neighbours (Gauss\u2013Seidel)"),
        ),
        default="SIMULTANEOUS",
    )
    tolerance: FloatProperty(
        name="Tolerance",
        description="Stop early once no vertex moves more than this fraction of the bounding-box "
        "diagonal in a step (0 = always run every iteration)",
        min=0.0, soft_max=0.01, default=0.0, step=0.01, precision=6,
    )
    vertex_group: StringProperty(
        name="Vertex Group",
        description="Vertices in this group (weight above 0) stay fixed; empty: none",
        default="",
    )
    invert_vertex_group: BoolProperty(
        name="Invert",
        description="Fix every vertex outside the group instead: smooth only the group",
        default=False,
    )
    pin_boundary: BoolProperty(
        name="Pin Boundary",
        description="Keep the vertices on open boundaries (holes, borders) fixed",
        default=False,
    )
    output: EnumProperty(
        name="Output",
        description="Where the result goes",
        items=(
            ("MESH", "Mesh", "Move the mesh vertices"),
            ("SHAPE_KEY", "New Shape Key", "Write the result into a new shape key and leave the mesh as it was"),
        ),
        default="MESH",
    )

    def copy_to(self, properties, names=OPERATOR_SETTINGS):
        """Set these settings on an operator's properties (a button's OperatorProperties)."""
        for name in names:
            setattr(properties, name, getattr(self, name))


def register():
    bpy.types.Scene.hc_smooth = bpy.props.PointerProperty(type=HCSmoothSettings, name="HC Smooth")


def unregister():
    del bpy.types.Scene.hc_smooth
