"""Mesh smoothing: the paper's HC on a mesh's umbrella, wrapped in what a scan needs (sections 4 and 6).

world (an object's stretch) -> welding (coincident vertices run as one) -> borders (what open borders
do) -> noise (is there noise, how much) -> amount (the Automatic Amount: iterations from the noise) ->
the smoothers in core.smoothing, or sharp_edges (Keep Sharp Edges, its amount from sharp_amount) ->
in_place (keep each move across the surface) -> volume (closed parts' volume back) -> collapse (a part
whose shape the run took away gets its input back); smooth runs them in that order. topology and parts
say which parts are closed and which vertices belong together; metrics and deviation measure what a run
changed for the report and the deviation map.
"""

from .amount import AmountChooser, MeshAmount, choose_amount
from .deviation import DeviationMap, deviation_colors, deviation_extent, deviation_map, normal_deviation
from .metrics import Change, measure_change
from .smooth import AUTO, DEFAULT_ALPHA, DEFAULT_BETA, DEFAULT_ITERATIONS, MeshReport, MeshSmoother, smooth_mesh

__all__ = [
    "AUTO",
    "AmountChooser",
    "Change",
    "DEFAULT_ALPHA",
    "DEFAULT_BETA",
    "DEFAULT_ITERATIONS",
    "DeviationMap",
    "MeshAmount",
    "MeshReport",
    "MeshSmoother",
    "choose_amount",
    "deviation_colors",
    "deviation_extent",
    "deviation_map",
    "measure_change",
    "normal_deviation",
    "smooth_mesh",
]
