"""CAD-like parts with sharp edges for bench_sharp_edges.py, built in code (no files, no downloads).

Each part is a solid made with manifold3d's booleans and hulls, then remeshed by MeshLab's isotropic
explicit remeshing (features kept at 30°) into near-equilateral triangles of about ``edge`` long, as a
scanner's mesh is: the constructive solid's long thin triangles would be no scan. Every part returns
(vertices (n, 3) float64, faces (f, 3) int64), closed and outward.

* ``bevelled_box``: a 2 × 1.4 × 1 box with every edge bevelled at 45° (0.15 wide).
* ``holed_cylinder``: a cylinder of radius 1 and height 1 with a through hole of radius 0.45, a swept
  grid (not remeshed: the remeshing folds triangles at its rims).
* ``fandisk``: a block with a cylindrical channel on top, a 45° chamfer on one side and a round boss:
  convex and concave creases, curved faces, creases meeting curved faces (a fandisk's kind of shape).
"""

import numpy as np

from bench import meshes


def _remeshed(solid, edge):
    import pymeshlab

    mesh = solid.to_mesh()
    vertices = np.asarray(mesh.vert_properties, np.float64)[:, :3]
    faces = np.asarray(mesh.tri_verts, np.int32)
    meshset = pymeshlab.MeshSet()
    meshset.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    length = getattr(pymeshlab, "PureValue", None) or pymeshlab.AbsoluteValue
    meshset.meshing_isotropic_explicit_remeshing(iterations=12, targetlen=length(edge), featuredeg=30.0)
    out = meshset.current_mesh()
    return out.vertex_matrix().copy(), out.face_matrix().astype(np.int64)


def bevelled_box(edge=0.035, size=(2.0, 1.4, 1.0), bevel=0.15):
    from manifold3d import Manifold

    half = np.asarray(size) / 2.0
    corners = []
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3)
    for axis in range(3):  # each corner pulled in by the bevel along the two other axes: 45° bevels
        corners.append(signs * np.where(np.arange(3) == axis, half, half - bevel))
    return _remeshed(Manifold.hull_points(np.concatenate(corners)), edge)


def holed_cylinder(edge=0.035, radius=1.0, hole=0.45, height=1.0):
    """The rectangle (hole..radius) x (0..height) of the (r, z) plane swept around the z axis: a grid of
    quads (split into triangles) like a torus's, the four rims on grid lines."""
    corners = np.array([[hole, 0.0], [radius, 0.0], [radius, height], [hole, height]])
    profile = []
    for a, b in zip(corners, np.roll(corners, -1, axis=0)):
        count = max(1, int(round(np.linalg.norm(b - a) / edge)))
        profile.append(a + (b - a) * np.arange(count)[:, None] / count)
    profile = np.concatenate(profile)
    around = int(round(2.0 * np.pi * (hole + radius) / 2.0 / edge))
    angle = np.linspace(0.0, 2.0 * np.pi, around, endpoint=False)[:, None]
    r, z = profile[:, 0][None, :], profile[:, 1][None, :]
    vertices = np.stack(np.broadcast_arrays(r * np.cos(angle), r * np.sin(angle), z), axis=-1).reshape(-1, 3)
    return vertices, _outward(vertices, meshes.wrapped_grid(around, len(profile)))


def _outward(vertices, faces):
    centre = vertices.mean(axis=0)
    a, b, c = (vertices[faces[:, k]] - centre for k in range(3))
    return faces if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() > 0 else faces[:, ::-1].copy()


def fandisk(edge=0.035):
    from manifold3d import Manifold

    block = Manifold.cube([2.0, 1.2, 1.0], True)
    channel = Manifold.cylinder(2.4, 0.35, 0.35, 256, True).rotate([0.0, 90.0, 0.0]).translate([0.0, 0.0, 0.55])
    chamfer = Manifold.cube([3.0, 1.0, 1.0], True).rotate([45.0, 0.0, 0.0]).translate([0.0, 0.6, -0.5])
    boss = Manifold.cylinder(0.3, 0.25, 0.25, 256).translate([0.6, -0.2, 0.45])
    return _remeshed((block - channel - chamfer) + boss, edge)


PARTS = {"bevelled_box": bevelled_box, "holed_cylinder": holed_cylinder, "fandisk": fandisk}
