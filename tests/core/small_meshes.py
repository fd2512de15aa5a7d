"""Small test meshes: (positions (n, 3) float64, edges (m, 2), faces list) with noise from a seed."""

import numpy as np


def edges_of(faces):
    pairs = set()
    for face in faces:
        for a, b in zip(face, list(face[1:]) + [face[0]]):
            pairs.add((min(a, b), max(a, b)))
    return np.array(sorted(pairs), dtype=np.int64).reshape(-1, 2)


def octahedron():
    p = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return p, faces


def cube_quads():
    p = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return p, faces


def pentagonal_prism():
    """Two pentagons (n-gons) and five quads."""
    angles = np.arange(5) * 2 * np.pi / 5
    ring = np.stack([np.cos(angles), np.sin(angles)], 1)
    p = np.concatenate([np.c_[ring, np.zeros(5)], np.c_[ring, np.ones(5)]])
    faces = [[4, 3, 2, 1, 0], [5, 6, 7, 8, 9]] + [[i, (i + 1) % 5, 5 + (i + 1) % 5, 5 + i] for i in range(5)]
    return p, faces


def grid(nx=5, ny=4):
    """An open triangulated patch with a boundary."""
    p = np.array([[x, y, 0.0] for y in range(ny) for x in range(nx)], float)
    faces = []
    for y in range(ny - 1):
        for x in range(nx - 1):
            a = y * nx + x
            faces += [[a, a + 1, a + nx + 1], [a, a + nx + 1, a + nx]]
    return p, faces


def uv_sphere(rings=8, segments=12):
    """A closed triangulated sphere of radius 1, outward-facing."""
    points = [[0, 0, 1]]
    for r in range(1, rings):
        theta = np.pi * r / rings
        for s in range(segments):
            phi = 2 * np.pi * s / segments
            points.append([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    points.append([0, 0, -1])
    last = len(points) - 1
    faces = []
    for s in range(segments):
        faces.append([0, 1 + s, 1 + (s + 1) % segments])
    for r in range(rings - 2):
        for s in range(segments):
            a = 1 + r * segments + s
            b = 1 + r * segments + (s + 1) % segments
            faces += [[a, a + segments, b], [b, a + segments, b + segments]]
    base = 1 + (rings - 2) * segments
    for s in range(segments):
        faces.append([base + s, last, base + (s + 1) % segments])
    return np.array(points, float), faces


def combined(*meshes):
    """Several meshes as disconnected parts of one."""
    positions, faces, offset = [], [], 0
    for i, (p, f) in enumerate(meshes):
        positions.append(p + 3.0 * i)
        faces += [[v + offset for v in face] for face in f]
        offset += len(p)
    return np.concatenate(positions), faces


def noisy(positions, sigma=0.05, seed=0):
    return positions + np.random.default_rng(seed).normal(scale=sigma, size=positions.shape)


def with_isolated(positions, faces, count=2, seed=1):
    """Append isolated vertices (no edges)."""
    extra = np.random.default_rng(seed).normal(size=(count, 3))
    return np.concatenate([positions, extra]), faces
