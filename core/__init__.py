"""HC Smooth's mathematics: NumPy/SciPy only, never bpy (paper: Vollmer, Mencl, Müller 1999).

The same package loads as ``core`` in tests and tools and as ``bl_ext.<repo>.hc_smooth.core`` in
Blender, so everything inside uses relative imports.
"""

from . import (
    borders,
    collapse,
    deviation,
    in_place,
    mesh_amount,
    metrics,
    sharp_edges,
    tiles,
    topology,
    volume,
    welding,
    world,
)
from .adjacency import Umbrella, umbrella_from_pairs, umbrella_operator
from .convergence import ConvergenceWarning, DivergenceError, convergence_message, in_convergence_region
from .deviation import DeviationMap, deviation_colors, deviation_extent, deviation_map, normal_deviation
from .mesh_amount import AmountChooser, MeshAmount, choose_amount
from .mesh_smoother import AUTO, DEFAULT_ALPHA, DEFAULT_BETA, DEFAULT_ITERATIONS, MeshReport, MeshSmoother, smooth_mesh
from .metrics import Change, measure_change
from .pointcloud import smooth_point_cloud
from .smoothing import METHODS, MODES, Cancelled, Smoothing, SmoothResult, hc_smooth, laplacian_smooth, smooth

__all__ = [
    "AUTO",
    "DEFAULT_ALPHA",
    "DEFAULT_BETA",
    "DEFAULT_ITERATIONS",
    "MeshReport",
    "MeshSmoother",
    "smooth_mesh",
    "Cancelled",
    "Change",
    "ConvergenceWarning",
    "DivergenceError",
    "DeviationMap",
    "MeshAmount",
    "METHODS",
    "MODES",
    "SmoothResult",
    "Smoothing",
    "Umbrella",
    "AmountChooser",
    "borders",
    "collapse",
    "choose_amount",
    "convergence_message",
    "deviation",
    "deviation_colors",
    "deviation_extent",
    "deviation_map",
    "hc_smooth",
    "in_place",
    "in_convergence_region",
    "laplacian_smooth",
    "mesh_amount",
    "metrics",
    "normal_deviation",
    "measure_change",
    "smooth",
    "sharp_edges",
    "smooth_point_cloud",
    "tiles",
    "topology",
    "umbrella_from_pairs",
    "umbrella_operator",
    "volume",
    "welding",
    "world",
]
