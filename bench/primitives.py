"""Blender's mesh primitives at their default settings, built in NumPy (the same vertices and faces as
``bpy.ops.mesh.primitive_*_add()`` up to vertex order), CAD-like parts and tiny parts, for the tests
of what the Automatic Amount does to meshes without noise.

Each function returns a Mesh: positions (n, 3) float64, faces (a list of vertex index lists, outward
for closed meshes) and edges (m, 2), the edges of the faces plus loose ones.
"""

from typing import NamedTuple

import numpy as np


class Mesh(NamedTuple):
    positions: np.ndarray
    faces: list
    edges: np.ndarray

    def triangles(self):
        """The faces as fans of triangles, (t, 3)."""
        return np.array([[face[0], face[k], face[k + 1]] for face in self.faces for k in range(1, len(face) - 1)])


def mesh(positions, faces, loose_edges=()):
    pairs = {tuple(sorted(pair)) for face in faces for pair in zip(face, list(face[1:]) + [face[0]])}
    pairs |= {tuple(sorted(pair)) for pair in loose_edges}
    edges = np.array(sorted(pairs), dtype=np.int64).reshape(-1, 2)
    return Mesh(np.asarray(positions, dtype=np.float64), [list(map(int, face)) for face in faces], edges)


def joined(*meshes):
    """Several meshes as the parts of one."""
    positions, faces, edges, offset = [], [], [], 0
    for part in meshes:
        positions.append(part.positions)
        faces += [[v + offset for v in face] for face in part.faces]
        edges.append(part.edges + offset)
        offset += len(part.positions)
    return Mesh(np.concatenate(positions), faces, np.concatenate(edges))


def moved(part, scale=1.0, offset=(0.0, 0.0, 0.0)):
    return Mesh(part.positions * scale + np.asarray(offset, float), part.faces, part.edges)


def median_edge(part):
    e = part.edges
    return float(np.median(np.linalg.norm(part.positions[e[:, 0]] - part.positions[e[:, 1]], axis=1)))


def with_noise(part, ratio, kind, seed=0):
    """(the part with Gaussian noise of ``ratio`` median edge lengths, along the area-weighted vertex
    normals (``kind`` "normal") or on every axis, that noise's standard deviation)."""
    sigma = ratio * median_edge(part)
    rng = np.random.default_rng(seed)
    if kind == "normal":
        triangles = part.triangles()
        a, b, c = (part.positions[triangles[:, k]] for k in range(3))
        face = np.cross(b - a, c - a)
        normals = np.zeros_like(part.positions)
        for k in range(3):
            np.add.at(normals, triangles[:, k], face)
        shift = normals / np.linalg.norm(normals, axis=1, keepdims=True) * rng.normal(0.0, sigma, (len(normals), 1))
    else:
        shift = rng.normal(0.0, sigma, part.positions.shape)
    return part._replace(positions=part.positions + shift), sigma


def _ring(count, radius=1.0, z=0.0):
    """Blender's circle: the first vertex on +y, counter-clockwise seen from +z."""
    angle = np.pi / 2 + 2 * np.pi * np.arange(count) / count
    return np.stack([radius * np.cos(angle), radius * np.sin(angle), np.full(count, z)], axis=1)


def cube():
    p = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    faces = [[0, 1, 3, 2], [2, 3, 7, 6], [6, 7, 5, 4], [4, 5, 1, 0], [2, 6, 4, 0], [7, 3, 1, 5]]
    return mesh(p, faces)


def plane():
    return mesh([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2, 3]])


def grid(subdivisions=10, size=2.0):
    """Blender's Grid: ``subdivisions`` quads a side (11 x 11 vertices at the default)."""
    side = subdivisions + 1
    u, v = np.meshgrid(np.linspace(-size / 2, size / 2, side), np.linspace(-size / 2, size / 2, side))
    p = np.stack([u.ravel(), v.ravel(), np.zeros(side * side)], axis=1)
    faces = [
        [j * side + i, j * side + i + 1, (j + 1) * side + i + 1, (j + 1) * side + i]
        for j in range(side - 1)
        for i in range(side - 1)
    ]
    return mesh(p, faces)


def circle(vertices=32, fill="NOTHING"):
    p = _ring(vertices)
    loop = [(i, (i + 1) % vertices) for i in range(vertices)]
    if fill == "NOTHING":
        return mesh(p, [], loop)
    if fill == "NGON":
        return mesh(p, [list(range(vertices))])
    centre = vertices
    return mesh(np.concatenate([p, [[0.0, 0.0, 0.0]]]), [[centre, i, (i + 1) % vertices] for i in range(vertices)])


def _caps(faces, p, bottom, top, fill, outward_bottom=True):
    """Caps of a tube whose rings are the index lists ``bottom`` and ``top`` (top None: a cone)."""
    count = len(bottom)
    rings = [(bottom, -1.0)] + ([(top, 1.0)] if top is not None else [])
    for ring, z in rings:
        if fill == "NGON":
            faces.append(list(reversed(ring)) if z < 0 else list(ring))
        elif fill == "TRIFAN":
            centre = len(p)
            p.append([0.0, 0.0, z])
            for i in range(count):
                a, b = ring[i], ring[(i + 1) % count]
                faces.append([centre, b, a] if z < 0 else [centre, a, b])


def cylinder(vertices=32, fill="NGON"):
    p = list(_ring(vertices, z=-1.0)) + list(_ring(vertices, z=1.0))
    bottom, top = list(range(vertices)), list(range(vertices, 2 * vertices))
    faces = [[bottom[i], bottom[(i + 1) % vertices], top[(i + 1) % vertices], top[i]] for i in range(vertices)]
    _caps(faces, p, bottom, top, fill)
    return mesh(np.array(p), faces)


def cone(vertices=32, fill="NGON"):
    p = list(_ring(vertices, z=-1.0)) + [[0.0, 0.0, 1.0]]
    apex, bottom = vertices, list(range(vertices))
    faces = [[bottom[i], bottom[(i + 1) % vertices], apex] for i in range(vertices)]
    _caps(faces, p, bottom, None, fill)
    return mesh(np.array(p), faces)


def uv_sphere(segments=32, rings=16):
    theta = np.pi * np.arange(1, rings) / rings  # from the north pole
    phi = 2 * np.pi * np.arange(segments) / segments + np.pi / 2
    s, c = np.sin(theta)[:, None], np.cos(theta)[:, None]
    p = np.stack([s * np.cos(phi), s * np.sin(phi), np.broadcast_to(c, s.shape * np.array([1, segments]))], -1)
    p = np.concatenate([[[0.0, 0.0, 1.0]], p.reshape(-1, 3), [[0.0, 0.0, -1.0]]])
    north, south = 0, len(p) - 1

    def at(ring, segment):
        return 1 + ring * segments + segment % segments

    faces = [[north, at(0, i), at(0, i + 1)] for i in range(segments)]
    faces += [
        [at(r, i), at(r + 1, i), at(r + 1, i + 1), at(r, i + 1)] for r in range(rings - 2) for i in range(segments)
    ]
    faces += [[south, at(rings - 2, i + 1), at(rings - 2, i)] for i in range(segments)]
    return mesh(p, faces)


def ico_sphere(subdivisions=2):
    """Blender's Ico Sphere: an icosahedron (a vertex at -z), its edges halved ``subdivisions`` - 1 times,
    every vertex on the unit sphere."""
    z = 1 / np.sqrt(5)
    lower = [[2 * z * np.cos(a), 2 * z * np.sin(a), -z] for a in -np.pi / 5 + 2 * np.pi * np.arange(5) / 5]
    upper = [[2 * z * np.cos(a), 2 * z * np.sin(a), z] for a in 2 * np.pi * np.arange(5) / 5]
    p = [[0.0, 0.0, -1.0]] + lower + upper + [[0.0, 0.0, 1.0]]
    faces = []
    for i in range(5):
        j = (i + 1) % 5
        faces += [[0, 1 + j, 1 + i], [11, 6 + i, 6 + j], [1 + i, 1 + j, 6 + i], [1 + j, 6 + j, 6 + i]]
    for _ in range(subdivisions - 1):
        middle, split = {}, []
        for a, b, c in faces:
            ab, bc, ca = (_middle(p, middle, u, v) for u, v in ((a, b), (b, c), (c, a)))
            split += [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
        faces = split
    return mesh(np.array(p), faces)


def _middle(points, middle, a, b):
    """The vertex halving edge (a, b), pushed onto the unit sphere (made once per edge)."""
    key = (min(a, b), max(a, b))
    if key not in middle:
        point = np.add(points[a], points[b])
        points.append(list(point / np.linalg.norm(point)))
        middle[key] = len(points) - 1
    return middle[key]


def torus(major_segments=48, minor_segments=12, major_radius=1.0, minor_radius=0.25):
    a = 2 * np.pi * np.arange(major_segments) / major_segments
    b = 2 * np.pi * np.arange(minor_segments) / minor_segments
    ring = major_radius + minor_radius * np.cos(b)
    p = np.stack(
        [
            np.cos(a)[:, None] * ring,
            np.sin(a)[:, None] * ring,
            np.broadcast_to(minor_radius * np.sin(b), (major_segments, minor_segments)),
        ],
        axis=-1,
    ).reshape(-1, 3)

    def at(i, j):
        return (i % major_segments) * minor_segments + j % minor_segments

    faces = [
        [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]
        for i in range(major_segments)
        for j in range(minor_segments)
    ]
    return mesh(p, faces)


PRIMITIVES = {
    "cube": cube,
    "plane": plane,
    "grid": grid,
    "circle": lambda: circle(fill="NOTHING"),
    "circle_ngon": lambda: circle(fill="NGON"),
    "circle_trifan": lambda: circle(fill="TRIFAN"),
    "uv_sphere": uv_sphere,
    "ico_sphere": ico_sphere,
    "cylinder_ngon": lambda: cylinder(fill="NGON"),
    "cylinder_trifan": lambda: cylinder(fill="TRIFAN"),
    "cylinder_open": lambda: cylinder(fill="NOTHING"),
    "cone_ngon": lambda: cone(fill="NGON"),
    "cone_trifan": lambda: cone(fill="TRIFAN"),
    "cone_open": lambda: cone(fill="NOTHING"),
    "torus": torus,
}


def rounded_box(segments=4, radius=0.2, cells=4):
    """A CAD-like part: a box of half-size 1 whose edges are rounded to ``radius`` in ``segments`` (even)
    flat steps, and its corners in spherical patches; quads, flat faces of ``cells`` x ``cells``."""
    inner = 1.0 - radius
    bevel = inner + radius * np.tan(np.linspace(0.0, np.pi / 4, segments // 2 + 1))[1:]  # cube coordinates
    ticks = np.concatenate([-bevel[::-1], np.linspace(-inner, inner, cells + 1), bevel])
    ticks[[0, -1]] = -1.0, 1.0
    count = ticks.size
    points, index = [], {}

    def vertex(key):
        if key not in index:
            index[key] = len(points)
            points.append([ticks[k] for k in key])
        return index[key]

    faces = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for side, end in ((1, count - 1), (-1, 0)):
            for i in range(count - 1):
                for j in range(count - 1):
                    corners = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        key = [0, 0, 0]
                        key[axis], key[u], key[v] = end, i + di, j + dj
                        corners.append(vertex(tuple(key)))
                    faces.append(corners if side > 0 else corners[::-1])
    cube_points = np.array(points)
    core_point = np.clip(cube_points, -inner, inner)
    out = cube_points - core_point
    positions = core_point + radius * out / np.linalg.norm(out, axis=1, keepdims=True)
    return mesh(positions, faces)


def tube(segments=32, outer=1.0, inner=0.5, depth=1.0, rings=2):
    """A CAD-like part: a cylinder with a coaxial hole (sharp rims), quads."""
    radii = np.linspace(outer, inner, rings + 1)
    # Around the cap from the outer rim to the inner one at the top, then back at the bottom.
    loops = [(r, depth / 2) for r in radii] + [(r, -depth / 2) for r in radii[::-1]]
    p = np.concatenate([_ring(segments, radius=r, z=z) for r, z in loops])
    count = len(loops)
    faces = []
    for k in range(count):
        a, b = k * segments, ((k + 1) % count) * segments
        faces += [[a + i, a + (i + 1) % segments, b + (i + 1) % segments, b + i] for i in range(segments)]
    return mesh(p, faces)


def subdivided_cube(cuts=3, triangulate=True):
    """Blender's Cube with Subdivide (``cuts`` cuts, each face a (cuts + 1)^2 grid of quads), optionally
    triangulated: vertices shared along the edges, faces outward."""
    side = cuts + 2
    t = np.linspace(-1.0, 1.0, side)
    index, positions, faces = {}, [], []

    def vertex(point):
        key = tuple(np.round(point, 9))
        if key not in index:
            index[key] = len(positions)
            positions.append(point)
        return index[key]

    for axis in range(3):
        for sign in (-1.0, 1.0):
            u_axis, v_axis = [(axis + 1) % 3, (axis + 2) % 3][:: int(sign)]
            grid = np.empty((side, side), dtype=int)
            for i, u in enumerate(t):
                for j, v in enumerate(t):
                    point = np.zeros(3)
                    point[axis], point[u_axis], point[v_axis] = sign, u, v
                    grid[i, j] = vertex(point)
            for i in range(side - 1):
                for j in range(side - 1):
                    quad = [grid[i, j], grid[i + 1, j], grid[i + 1, j + 1], grid[i, j + 1]]
                    faces += [quad[:3], [quad[0], quad[2], quad[3]]] if triangulate else [quad]
    return mesh(np.array(positions), faces)


CAD = {"rounded_box": rounded_box, "chamfered_box": lambda: rounded_box(segments=2), "tube": tube}


def two_vertices():
    return mesh([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [], [(0, 1)])


def triangle():
    return mesh([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[0, 1, 2]])


def tetrahedron():
    return mesh(
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )


TINY = {"two_vertices": two_vertices, "triangle": triangle, "tetrahedron": tetrahedron}
