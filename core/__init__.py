"""HC Smooth's mathematics: NumPy/SciPy only, never bpy (paper: Vollmer, Mencl, Müller 1999).

The same package loads as ``core`` in tests and tools and as ``bl_ext.<repo>.hc_smooth.core`` in
Blender, so everything inside uses relative imports. ``__all__`` below is core's public surface: the
Blender side (operators, ui, nodes), cli/ and settings_spec use these names and no module inside.

The smoothers (the paper's, on any umbrella)
    hc_smooth, laplacian_smooth, smooth, Smoothing, SmoothResult, METHODS, MODES: HC (section 4) and
    the Laplacian variants (section 3), run to the end or in slices. Cancelled: a progress callback
    said stop. BLOW_UP_FACTOR: how far a run's bounding box may grow before it counts as blown up.
    Umbrella, umbrella_operator, umbrella_from_pairs: the neighbourhoods the smoothers average over.
Convergence (section 5)
    in_convergence_region, convergence_message, convergence_lines, ConvergenceWarning,
    DivergenceError: whether alpha and beta settle on a shape (Theorem 5.2), as a sentence or panel lines.
Meshes (core/mesh)
    smooth_mesh, MeshSmoother, MeshReport, AUTO, DEFAULT_ALPHA, DEFAULT_BETA, DEFAULT_ITERATIONS: the
    mesh pipeline and its defaults. choose_amount, AmountChooser, MeshAmount, MAX_ITERATIONS: the
    Automatic Amount and the most iterations it chooses. measure_input, InputMeasure, measure_change,
    Change: what a run changed (the report). deviation_map, DeviationMap, normal_deviation,
    deviation_extent, deviation_colors: the deviation map. closed_from_corners: whether Blender-style
    faces close a surface; every_edge_shared: whether they leave no seam to weld. world_frame,
    to_frame, from_frame: an object's stretch (its world-space shape). tile_rings, tile_margin,
    tile_boxes, tiled_problem, tiles_choose, region_amount, TiledVolume: a mesh larger than memory smoothed in
    tiles (TiledVolume: its closed parts' volume given back, from each tile's piece; tile_volumes: its volume
    measured).
Point clouds (core/pointcloud, section 7)
    smooth_point_cloud, PointCloudSmoother: the RFS-mesh pipeline. collinear: points no surface can
    join. reach_gap_problem: why a reach and gap cannot go together. matched_alpha,
    MAX_POINT_CLOUD_STEPS: the Automatic Amount's alpha for its longest run.
Geometry shared by all (core/geometry)
    fan_triangles, face_normals, face_vectors, unit_rows, vertex_normals.
Checks and threads
    nonfinite_rows: rows of an array with a NaN or infinite value. in_background: a Future of a task
    run on a thread of its own.
"""

from .adjacency import Umbrella, umbrella_from_pairs, umbrella_operator
from .convergence import (
    ConvergenceWarning,
    DivergenceError,
    convergence_lines,
    convergence_message,
    in_convergence_region,
)
from .geometry import face_normals, face_vectors, fan_triangles, unit_rows, vertex_normals
from .mesh.amount import MAX_ITERATIONS, AmountChooser, MeshAmount, choose_amount
from .mesh.deviation import DeviationMap, deviation_colors, deviation_extent, deviation_map, normal_deviation
from .mesh.metrics import Change, InputMeasure, enclosed_volume, measure_change, measure_input
from .mesh.smooth import AUTO, DEFAULT_ALPHA, DEFAULT_BETA, DEFAULT_ITERATIONS, MeshReport, MeshSmoother, smooth_mesh
from .mesh.tile_volume import TiledVolume, tile_volumes
from .mesh.tiles import region_amount, tile_boxes, tile_margin, tile_rings, tiled_problem, tiles_choose
from .mesh.topology import closed_from_corners, every_edge_shared
from .mesh.world import frame as world_frame
from .mesh.world import from_frame, to_frame
from .parallel import in_background
from .pointcloud import PointCloudSmoother, smooth_point_cloud
from .pointcloud.geometry import collinear
from .pointcloud.noise import MAX_STEPS as MAX_POINT_CLOUD_STEPS
from .pointcloud.noise import matched_alpha
from .pointcloud.sdg import reach_gap_problem
from .smoothing import (
    BLOW_UP_FACTOR,
    METHODS,
    MODES,
    Cancelled,
    Smoothing,
    SmoothResult,
    hc_smooth,
    laplacian_smooth,
    smooth,
)
from .validation import nonfinite_rows

__all__ = [
    # the smoothers
    "BLOW_UP_FACTOR",
    "Cancelled",
    "METHODS",
    "MODES",
    "SmoothResult",
    "Smoothing",
    "Umbrella",
    "hc_smooth",
    "laplacian_smooth",
    "smooth",
    "umbrella_from_pairs",
    "umbrella_operator",
    # convergence
    "ConvergenceWarning",
    "DivergenceError",
    "convergence_lines",
    "convergence_message",
    "in_convergence_region",
    # meshes
    "AUTO",
    "AmountChooser",
    "Change",
    "DEFAULT_ALPHA",
    "DEFAULT_BETA",
    "DEFAULT_ITERATIONS",
    "DeviationMap",
    "InputMeasure",
    "MAX_ITERATIONS",
    "MeshAmount",
    "MeshReport",
    "MeshSmoother",
    "choose_amount",
    "closed_from_corners",
    "every_edge_shared",
    "deviation_colors",
    "deviation_extent",
    "deviation_map",
    "from_frame",
    "measure_change",
    "enclosed_volume",
    "measure_input",
    "normal_deviation",
    "region_amount",
    "smooth_mesh",
    "tile_boxes",
    "tile_margin",
    "tile_rings",
    "tiled_problem",
    "tiles_choose",
    "TiledVolume",
    "tile_volumes",
    "to_frame",
    "world_frame",
    # point clouds
    "MAX_POINT_CLOUD_STEPS",
    "PointCloudSmoother",
    "collinear",
    "matched_alpha",
    "reach_gap_problem",
    "smooth_point_cloud",
    # geometry
    "face_normals",
    "face_vectors",
    "fan_triangles",
    "unit_rows",
    "vertex_normals",
    # checks and threads
    "in_background",
    "nonfinite_rows",
]
