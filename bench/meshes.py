"""Closed triangle meshes for benchmarks, generated with NumPy alone (no files, no downloads).

Every generator returns (vertices (n, 3) float64, faces (f, 3) int64) with outward-facing
triangles, so the signed volume of the result is positive and ``core.measure_change`` sees a closed
mesh. Helpers add seeded noise, derive the undirected edge list, and renumber vertices.
"""

import numpy as np


def torus(n_vertices, ratio=2.5, minor_radius=0.4):
    """A torus with about ``n_vertices`` vertices on a regular grid (valence 6 everywhere).

    The grid counts follow the ratio of the circumferences (R/r = ``ratio``) so the quads, split into
    two triangles each, are nearly square. Vertices come in grid order (good memory locality).
    """
    if n_vertices < 9:
        raise ValueError("a torus needs at least 9 vertices (3 x 3 grid)")
    around_tube = max(3, int(round(np.sqrt(n_vertices / ratio))))
    around_axis = max(3, int(round(n_vertices / around_tube)))
    major = ratio * minor_radius
    u = np.linspace(0.0, 2.0 * np.pi, around_axis, endpoint=False)[:, None]
    v = np.linspace(0.0, 2.0 * np.pi, around_tube, endpoint=False)[None, :]
    ring = major + minor_radius * np.cos(v)
    vertices = np.stack(
        np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), minor_radius * np.sin(v)), axis=-1
    ).reshape(-1, 3)
    return vertices, wrapped_grid(around_axis, around_tube)


def wrapped_grid(rows, columns):
    """(2 rows columns, 3) int64 triangles of a rows x columns vertex grid (vertex i columns + j) closed in
    both directions, each quad split along its diagonal from (i, j) to (i + 1, j + 1): a torus's faces."""
    i, j = np.meshgrid(np.arange(rows), np.arange(columns), indexing="ij")
    a = i * columns + j
    b = ((i + 1) % rows) * columns + j
    c = ((i + 1) % rows) * columns + (j + 1) % columns
    d = i * columns + (j + 1) % columns
    return np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]).astype(
        np.int64
    )


def torus_volume(ratio=2.5, minor_radius=0.4):
    """Volume of the smooth torus that ``torus`` samples: 2 pi^2 R r^2."""
    return 2.0 * np.pi**2 * ratio * minor_radius * minor_radius**2


def icosphere(level):
    """A unit icosphere subdivided ``level`` times: 10 * 4**level + 2 vertices (163,842 at level 7)."""
    t = (1.0 + 5.0**0.5) / 2.0
    vertices = np.array(
        [
            [-1, t, 0],
            [1, t, 0],
            [-1, -t, 0],
            [1, -t, 0],
            [0, -1, t],
            [0, 1, t],
            [0, -1, -t],
            [0, 1, -t],
            [t, 0, -1],
            [t, 0, 1],
            [-t, 0, -1],
            [-t, 0, 1],
        ],
        float,
    )
    faces = np.array(
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ],
        np.int64,
    )
    vertices /= np.linalg.norm(vertices, axis=1, keepdims=True)
    for _ in range(level):
        n = vertices.shape[0]
        # One new vertex per undirected edge, found by its sorted key; each face splits into four.
        corners = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        keys = np.minimum(corners[:, 0], corners[:, 1]) * n + np.maximum(corners[:, 0], corners[:, 1])
        unique, inverse = np.unique(keys, return_inverse=True)
        middle = (vertices[unique // n] + vertices[unique % n]) / 2.0
        middle /= np.linalg.norm(middle, axis=1, keepdims=True)
        vertices = np.concatenate([vertices, middle])
        ab, bc, ca = (n + inverse.reshape(-1, 3)).T
        a, b, c = faces.T
        faces = np.concatenate([np.stack(f, -1) for f in ([a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca])])
    return vertices, faces


def bbox_diagonal(vertices):
    return float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))


def add_noise(vertices, fraction=0.01, seed=0):
    """Isotropic Gaussian noise, sigma = ``fraction`` of the bounding-box diagonal per coordinate."""
    rng = np.random.default_rng(seed)
    sigma = fraction * bbox_diagonal(vertices)
    return vertices + rng.normal(0.0, sigma, size=vertices.shape)


def edges_from_faces(faces):
    """Undirected edges (each once, low index first) of a triangle mesh, as Blender would list them."""
    pairs = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    n = int(faces.max()) + 1 if faces.size else 0
    keys = np.unique(np.minimum(pairs[:, 0], pairs[:, 1]) * n + np.maximum(pairs[:, 0], pairs[:, 1]))
    return np.stack([keys // n, keys % n], axis=1)


def shuffled(vertices, faces, seed=0):
    """The same mesh with its vertices renumbered at random (scanner output has no useful order)."""
    order = np.random.default_rng(seed).permutation(vertices.shape[0])
    new_index = np.empty_like(order)
    new_index[order] = np.arange(order.size)
    return vertices[order], new_index[faces]
