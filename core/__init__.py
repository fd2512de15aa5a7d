"""HC Smooth's mathematics: NumPy/SciPy only, never bpy (paper: Vollmer, Mencl, Müller 1999).

The same package loads as ``core`` in tests and tools and as ``bl_ext.<repo>.hc_smooth.core`` in
Blender, so everything inside uses relative imports.
"""

from .adjacency import Umbrella, umbrella_from_pairs, umbrella_operator
from .convergence import ConvergenceWarning, DivergenceError, convergence_message, in_convergence_region
from .mesh.amount import AmountChooser, MeshAmount, choose_amount
from .mesh.deviation import DeviationMap, deviation_colors, deviation_extent, deviation_map, normal_deviation
from .mesh.metrics import Change, measure_change
from .mesh.smooth import AUTO, DEFAULT_ALPHA, DEFAULT_BETA, DEFAULT_ITERATIONS, MeshReport, MeshSmoother, smooth_mesh
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
    "choose_amount",
    "convergence_message",
    "deviation_colors",
    "deviation_extent",
    "deviation_map",
    "hc_smooth",
    "in_convergence_region",
    "laplacian_smooth",
    "normal_deviation",
    "measure_change",
    "smooth",
    "smooth_point_cloud",
    "umbrella_from_pairs",
    "umbrella_operator",
]
