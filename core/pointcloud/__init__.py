"""Point-cloud smoothing through the RFS mesh (paper section 7).

spanning_tree (exact EMST) -> sdg (surface description graph) -> rfs (RFS mesh) -> swap (edge
swapping) -> smooth (HC alternating with swapping); noise (noise / sample spacing estimate) picks
how much smoothing the run does, local_amount how much of it each point takes.
"""

from .noise import NoiseEstimate, estimate_noise
from .rfs import RFSMesh, rfs_mesh
from .sdg import surface_description_graph
from .smooth import PointCloudReport, PointCloudSmoother, smooth_point_cloud

__all__ = [
    "NoiseEstimate",
    "PointCloudReport",
    "PointCloudSmoother",
    "RFSMesh",
    "estimate_noise",
    "rfs_mesh",
    "smooth_point_cloud",
    "surface_description_graph",
]
