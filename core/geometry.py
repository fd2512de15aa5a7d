"""Triangle and edge geometry shared by core/mesh, core/pointcloud and cli/formats, each fact once.

Fans (``fan_triangles``: polygons as triangles), face normals (unit, (0, 0, 0) for a face without
area: a caller that wants another mark, such as NaN, sets it explicitly), area-weighted vertex normals,
the median edge length (one sampling rule), and the projection onto the deviation limit (the ball of
``radius`` around each vertex's input position).

Examples
--------
>>> import numpy as np
>>> from core import geometry
>>> points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
>>> geometry.face_normals(points, np.array([[0, 1, 2], [0, 3, 3]])).tolist()
[[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]
"""

import numpy as np

from . import parallel
from .parallel import BLOCK, TRIANGLE_BLOCK, VECTOR_BLOCK
from .slices import to_end

# The median edge length of a mesh with more than EDGE_SAMPLE_FROM row entries: of an even sample of EDGE_SAMPLE.
EDGE_SAMPLE_FROM = 1 << 21
EDGE_SAMPLE = 1 << 16


def fan_triangles(faces):
    """Triangles (t, 3) of a fan from each face's first corner (triangles come back as they are, no copy).

    Parameters
    ----------
    faces : (f, k) array_like of int, list of sequences, or (offsets, corner_verts)
        An (f, k) integer array, a list of faces (vertex index sequences, of any sizes), or a pair
        (offsets, corner_verts) as Blender stores polygons (offsets of length f + 1: face i has
        corners corner_verts[offsets[i]:offsets[i + 1]]).

    Returns
    -------
    (t, 3) int ndarray

    Raises
    ------
    ValueError
        Faces of fewer than three corners, or offsets that do not fit ``corner_verts``.

    Examples
    --------
    >>> from core import geometry
    >>> geometry.fan_triangles([[0, 1, 2, 3]]).tolist()
    [[0, 1, 2], [0, 2, 3]]
    >>> geometry.fan_triangles(([0, 3, 7], [0, 1, 2, 0, 2, 3, 4])).tolist()
    [[0, 1, 2], [0, 2, 3], [0, 3, 4]]
    """
    if isinstance(faces, list) and len({len(face) for face in faces}) > 1:  # a list of faces of mixed sizes
        faces = (np.cumsum([0] + [len(face) for face in faces]), np.concatenate(faces))
    if isinstance(faces, tuple):
        offsets, corners = _offsets_and_corners(faces)
        if corners.size == 3 * (offsets.size - 1):  # no face has fewer than three corners: all are triangles
            return corners.reshape(-1, 3)
    else:
        array = _indices(faces)
        if array.ndim != 2 or array.shape[1] < 3:
            raise ValueError(f"faces must have shape (f, k) with k >= 3, got {array.shape}")
        if array.shape[1] == 3:
            return array
        corners = array.ravel()
        offsets = np.arange(array.shape[0] + 1, dtype=np.int64) * array.shape[1]
    return _fans(offsets, corners)


def _offsets_and_corners(faces):
    offsets, corners = (_indices(a) for a in faces)
    if (
        offsets.ndim != 1
        or offsets.size == 0
        or offsets[0] != 0
        or offsets[-1] != corners.size
        or np.any(np.diff(offsets) < 3)
    ):
        raise ValueError(
            "faces as (offsets, corner_verts) need offsets from 0 to len(corner_verts), at least 3 corners per face"
        )
    return offsets, corners


def _fans(offsets, corners):
    sizes = np.diff(offsets)
    if sizes.size and corners.size == sizes[0] * sizes.size and np.all(sizes == sizes[0]):
        # All faces alike (all quads...): the fans are column picks of an (f, k) view.
        k = int(sizes[0])
        grid = corners.reshape(-1, k)
        return np.stack([grid[:, [0, j + 1, j + 2]] for j in range(k - 2)], axis=1).reshape(-1, 3)
    face_of_triangle = np.repeat(np.arange(sizes.size), sizes - 2)
    # Triangle k of face f: corners (0, k+1, k+2) counted from the face's first corner.
    k = np.arange(face_of_triangle.size) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
    first = offsets[face_of_triangle]
    return np.stack([corners[first], corners[first + k + 1], corners[first + k + 2]], axis=1)


def _indices(array):
    """An integer array as given (int32 stays int32), anything else as int64."""
    array = np.asarray(array)
    return array if np.issubdtype(array.dtype, np.integer) else array.astype(np.int64)


def face_vectors(points, triangles):
    """(t, 3) cross products (p1 - p0) x (p2 - p0) of the triangles: the normal (right-hand rule over
    the corners) times twice the area.

    Examples
    --------
    >>> import numpy as np, core
    >>> core.face_vectors(np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0]], dtype=float), np.array([[0, 1, 2]])).tolist()
    [[0.0, 0.0, 4.0]]
    """
    return _cross_block(points, triangles).T.copy()


def _cross_block(points, triangles):
    """(3, t) rows of (p1 - p0) x (p2 - p0), from one gather per corner and coordinate."""
    p = [tuple(points[triangles[:, k], j] for j in range(3)) for k in range(3)]
    e1 = [p[1][j] - p[0][j] for j in range(3)]
    e2 = [p[2][j] - p[0][j] for j in range(3)]
    return np.stack([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]])


def face_normals(points, triangles, out=None):
    """(t, 3) unit normals of the triangles (right-hand rule over the corners), in ``out`` if given;
    (0, 0, 0) for a triangle without area. Worked in blocks on the threads.

    Examples
    --------
    >>> import numpy as np, core
    >>> points = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0]], dtype=float)
    >>> core.face_normals(points, np.array([[0, 1, 2], [0, 0, 1]])).tolist()
    [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]
    """
    points, triangles = np.asarray(points), np.asarray(triangles)
    if out is None:
        dtype = points.dtype if np.issubdtype(points.dtype, np.floating) else np.float64
        out = np.empty((triangles.shape[0], 3), dtype=dtype)

    def block(lo, hi):
        normal = _cross_block(points, triangles[lo:hi])
        double_area = np.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
        good = double_area > 0.0
        if good.all():
            normal /= double_area
        else:
            np.divide(normal, double_area, out=normal, where=good)
            normal[:, ~good] = 0.0
        out[lo:hi] = normal.T

    parallel.run_chunks(block, triangles.shape[0], BLOCK)
    return out


def centroid(points):
    """The mean of (n, 3) points, in float64 ((0, 0, 0) for none): summed a block at a time as coordinate
    rows, where a sum down the columns of (n, 3) rows strides through memory at several times the cost.

    Examples
    --------
    >>> import numpy as np
    >>> from core import geometry
    >>> geometry.centroid(np.array([[0, 0, 0], [2, 4, 6]], dtype=np.float32)).tolist()
    [1.0, 2.0, 3.0]
    """
    points = np.asarray(points)
    total = np.zeros(3)
    for start in range(0, points.shape[0], VECTOR_BLOCK):
        total += np.ascontiguousarray(points[start : start + VECTOR_BLOCK].T).sum(axis=1, dtype=np.float64)
    return total / max(points.shape[0], 1)


def unit_rows(vectors):
    """(k, 3) rows scaled to length 1, (0, 0, 0) for a zero row.

    Examples
    --------
    >>> import numpy as np, core
    >>> core.unit_rows(np.array([[3.0, 0, 4], [0, 0, 0]])).tolist()
    [[0.6, 0.0, 0.8], [0.0, 0.0, 0.0]]
    """
    length = np.linalg.norm(vectors, axis=1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)


# The six entries of a symmetric 3 x 3 matrix, (row, column), in the order this module's eigen solvers take them.
SYMMETRIC_ENTRIES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def smallest_eigenvectors(xx, yy, zz, xy, xz, yz):
    """Unit eigenvectors of the smallest eigenvalue of the symmetric 3 x 3 matrices given by their six
    entries (each (s,)): the eigenvalue in closed form (trigonometric), the vector as the longest cross
    product of two rows of the matrix minus it. Vectorized, where a batched eigh spends most of its time
    on per-matrix overhead; rows with no clear smallest direction (collinear points) fall back to eigh."""
    mean, spread, angle = _trigonometric(xx, yy, zz, xy, xz, yz)
    smallest = mean + 2.0 * spread * np.cos(angle + 2.0 * np.pi / 3.0)
    rows = np.stack(
        [
            np.stack([xx - smallest, xy, xz], axis=1),
            np.stack([xy, yy - smallest, yz], axis=1),
            np.stack([xz, yz, zz - smallest], axis=1),
        ]
    )
    crosses = np.stack([np.cross(rows[0], rows[1]), np.cross(rows[0], rows[2]), np.cross(rows[1], rows[2])])
    lengths = np.einsum("csi,csi->cs", crosses, crosses)
    best = lengths.argmax(axis=0)
    normal = crosses[best, np.arange(best.size)]
    length = np.sqrt(lengths[best, np.arange(best.size)])
    # A cross product this short against the matrix's size: two eigenvalues (nearly) tie at the bottom.
    unclear = ~(length > 1e-9 * (mean * 3.0) ** 2)
    length[unclear] = 1.0
    normal /= length[:, None]
    if unclear.any():
        matrices = np.stack([xx, xy, xz, xy, yy, yz, xz, yz, zz], axis=1)[unclear].reshape(-1, 3, 3)
        normal[unclear] = np.linalg.eigh(matrices)[1][:, :, 0]
    return normal


def symmetric_eigenvalues(xx, yy, zz, xy, xz, yz):
    """(3, s) the eigenvalues of the symmetric 3 x 3 matrices given by their six entries (each (s,)),
    ascending, in closed form (as ``smallest_eigenvectors`` finds the smallest).

    Examples
    --------
    >>> import numpy as np
    >>> from core import geometry
    >>> geometry.symmetric_eigenvalues(*np.array([[2.0], [3.0], [1.0], [0.0], [0.0], [0.0]])).round(9).ravel().tolist()
    [1.0, 2.0, 3.0]
    """
    mean, spread, angle = _trigonometric(xx, yy, zz, xy, xz, yz)
    low = mean + 2.0 * spread * np.cos(angle + 2.0 * np.pi / 3.0)
    high = mean + 2.0 * spread * np.cos(angle)
    return np.stack([low, 3.0 * mean - low - high, high])


def _trigonometric(xx, yy, zz, xy, xz, yz):
    """(mean, spread, angle): the eigenvalues of each symmetric matrix are mean + 2 spread cos(angle + 2 pi k / 3)."""
    mean = (xx + yy + zz) / 3.0
    off = xy * xy + xz * xz + yz * yz
    spread = np.sqrt(((xx - mean) ** 2 + (yy - mean) ** 2 + (zz - mean) ** 2 + 2.0 * off) / 6.0)
    safe = np.where(spread > 0, spread, 1.0)
    # det((M - mean I) / spread) / 2 = cos(3 angle) of the trigonometric solution.
    bx, by, bz = (xx - mean) / safe, (yy - mean) / safe, (zz - mean) / safe
    bxy, bxz, byz = xy / safe, xz / safe, yz / safe
    half_det = (bx * (by * bz - byz * byz) - bxy * (bxy * bz - byz * bxz) + bxz * (bxy * byz - by * bxz)) / 2.0
    return mean, spread, np.arccos(np.clip(half_det, -1.0, 1.0)) / 3.0


def smallest_group_axes(owner, spread, groups):
    """(groups, 3): per group, the unit eigenvector of the smallest eigenvalue of the sum of spread spread^T
    over its rows (``owner`` (k,) in [0, groups), ``spread`` (k, 3)): the normal of a PCA plane fit."""
    return smallest_eigenvectors(
        *(np.bincount(owner, spread[:, a] * spread[:, b], groups) for a, b in SYMMETRIC_ENTRIES)
    )


def vertex_normals(positions, triangles, dtype=np.float64, agreement=False):
    """Area-weighted unit vertex normals of a triangle mesh (zero where no face touches a vertex), summed in
    float64 and handed back as ``dtype``. ``agreement``: also (n,) float64 |sum_f a_f n_f| / sum_f a_f over
    each vertex's faces f (a_f their areas, n_f their unit normals): 1 where they all face one way, less
    where they turn (0 where no face touches it).

    Examples
    --------
    >>> import numpy as np
    >>> from core import geometry
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> geometry.vertex_normals(positions, triangles).round(3).tolist()
    [[-0.577, -0.577, -0.577], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    >>> geometry.vertex_normals(positions, triangles, agreement=True)[1].round(3).tolist()  # a corner everywhere
    [0.577, 0.268, 0.268, 0.268]
    """
    normals = to_end(vertex_normal_steps(positions, triangles, agreement))
    unit = np.ascontiguousarray(normals[:3].T, dtype=dtype)
    return (unit, normals[3]) if agreement else unit


def vertex_normal_steps(positions, triangles, agreement=False, faces=None):
    """``vertex_normals`` in slices, as float64 coordinate rows: a generator that yields (None) after each
    round of blocks of triangles and returns the (3, n) unit normals, with ``agreement`` as a fourth row
    (no transposed copy: for callers that read them a block of vertices at a time). ``faces``: a (3, t) and
    a (t,) array the triangles' unit normals ((0, 0, 0) without area) and twice-areas are written to, from
    the same products.

    Examples
    --------
    >>> import numpy as np
    >>> from core import geometry
    >>> from core.slices import to_end
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    >>> to_end(geometry.vertex_normal_steps(positions, np.array([[0, 1, 2]]), agreement=True)).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]
    """
    planar = np.ascontiguousarray(np.asarray(positions).T)
    steps = normals_and_measures(
        planar, np.asarray(triangles), None, 1, None, measure=False, agreement=agreement, faces=faces
    )
    return (yield from steps)[0]


def normals_and_measures(
    after,
    triangles,
    part_of_vertex,
    parts,
    centre,
    block=TRIANGLE_BLOCK,
    measure=True,
    agreement=False,
    faces=None,
):
    """(normals, measures) in slices, of (3, n) planar positions: the unit vertex normals (area-weighted,
    float64 (3, n)) and per part, (2, parts), its volume less the ``centre`` (None: the origin) (times 6)
    and its area (times 2); ``measure`` False: the normals alone (measures zero); ``agreement``: the
    normals get a fourth row, how far each vertex's faces agree (``vertex_normals``); ``faces``: as
    ``vertex_normal_steps``'. Each ``block`` of triangles is measured on the threads, then its normals
    added at their corners block by block: the same numbers whatever the thread count."""
    normals = np.zeros((4 if agreement else 3, after.shape[1]))

    def measured(start, stop):
        block = np.ascontiguousarray(triangles[start:stop].T, dtype=index_dtype(after.shape[1]))
        a, b, c = corner_rows(after, block, centre)
        volume = dot(a, cross(b, c)) if measure else None
        b -= a
        c -= a
        if agreement:  # the twice-areas summed beside the twice-area normals
            twice = np.empty((4, b.shape[1]))
            twice[:3] = cross(b, c)
            np.sqrt(dot(twice, twice), out=twice[3])
        else:
            twice = cross(b, c)
        if faces is not None:
            length = twice[3] if agreement else np.sqrt(dot(twice, twice))
            faces[1][start:stop] = length
            faces[0][:, start:stop] = twice[:3] / np.where(length > 0.0, length, 1.0)
        sums = part_sums([volume, np.sqrt(dot(twice, twice))], part_of_vertex, block, parts) if measure else 0.0
        return block, twice, sums

    measures = np.zeros((2, parts))
    for blocks in in_rounds(measured, len(triangles), block):
        for corners, twice, sums in blocks:
            _add_at_corners(normals, corners, twice)
            measures += sums
        yield

    def unit(start, stop):
        rows = normals[:3, start:stop]
        length = np.sqrt(dot(rows, rows))
        if agreement:
            area = normals[3, start:stop]
            area[:] = np.divide(length, area, out=np.zeros_like(length), where=area > 0.0)
        rows /= np.where(length > 0.0, length, 1.0)

    parallel.run_chunks(unit, normals.shape[1], VECTOR_BLOCK)
    return normals, measures


def part_sums(terms, part_of_vertex, block, parts):
    """(len(terms), parts): each per-triangle term summed over each part's triangles."""
    if parts == 1:
        return np.array([[term.sum()] for term in terms])
    owner = part_of_vertex[block[0]]
    return np.array([np.bincount(owner, weights=term, minlength=parts) for term in terms])


def index_dtype(n):
    return np.int32 if n < np.iinfo(np.int32).max else np.int64


def _add_at_corners(sums, corners, values):
    """sums[:, v] += values[:, i] for each corner v of triangle i (``corners``: (3, t) columns): by a
    count over the block's span of vertices where it is short (meshes numbered with some locality),
    else one at a time."""
    low, high = int(corners.min()), int(corners.max()) + 1
    for at in corners:
        if high - low <= 4 * corners.shape[1]:
            at = at - low
            for j in range(len(values)):
                sums[j, low:high] += np.bincount(at, weights=values[j], minlength=high - low)
        else:
            for j in range(len(values)):
                np.add.at(sums[j], at, values[j])


def corner_rows(planar, columns, centre=None):
    """(a, b, c): the corners of the triangles (``columns``: their (3, t) corner columns) in (3, n)
    ``planar`` points, as float64 (3, t) rows (less ``centre``)."""
    corners = np.empty((3, 3, columns.shape[1]))
    for k, at in enumerate(columns):
        for j in range(3):
            corners[k, j] = planar[j].take(at)
            if centre is not None:
                corners[k, j] -= centre[j]
    return corners


def cross(b, c):
    """Column-wise b x c of (3, t) rows, (3, t)."""
    return np.stack((b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]))


def dot(a, b):
    """Column-wise a . b of (3, t) rows."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def in_rounds(function, size, block=TRIANGLE_BLOCK):
    """Generator of rounds: function(start, stop) for consecutive blocks of ``block`` elements of
    range(size), one block per thread at a time; yields each round's results in block order. The
    blocks are the same whatever the thread count."""
    starts = range(0, size, block)
    per_round = parallel.thread_count()
    for first in range(0, len(starts), per_round):
        tasks = [
            lambda start=start: function(start, min(start + block, size)) for start in starts[first : first + per_round]
        ]
        yield parallel.run_all(tasks)


def median_edge_length(points, operator):
    """The median length of the edges (i, j), i < j, of the operator's rows, 0 without edges; on big
    meshes (more than EDGE_SAMPLE_FROM row entries) of an even sample of EDGE_SAMPLE of the rows'
    entries. The lengths are measured in blocks of rows."""
    entries = operator.indices.size
    if entries > EDGE_SAMPLE_FROM:
        picked = np.linspace(0, entries - 1, EDGE_SAMPLE).astype(np.int64)
        rows = np.searchsorted(operator.indptr, picked, side="right") - 1
        lengths = _upper_lengths(points, rows, operator.indices[picked])
    else:
        lengths = []
        for low in range(0, operator.n_vertices, BLOCK):
            high = min(low + BLOCK, operator.n_vertices)
            rows = np.repeat(np.arange(low, high), operator.degree[low:high])
            lengths.append(_upper_lengths(points, rows, operator.indices[operator.indptr[low] : operator.indptr[high]]))
        lengths = np.concatenate(lengths) if lengths else np.zeros(0)
    return float(np.median(lengths)) if lengths.size else 0.0


def _upper_lengths(points, rows, columns):
    """The lengths of the pairs (row, column) with row < column."""
    upper = columns > rows
    difference = np.asarray(points[rows[upper]], np.float64) - np.asarray(points[columns[upper]], np.float64)
    return np.sqrt(np.einsum("ij,ij->i", difference, difference))


def project_within(planar, start, radius, squared=None):
    """(3, k) ``planar`` points projected, in place, onto the balls of ``radius`` (a distance, or one per
    column) around (3, k) ``start``: the deviation limit. ``squared``, radius * radius, if the caller
    keeps it."""
    away = np.subtract(planar, start)
    squares = np.einsum("ij,ij->j", away, away)
    per_vertex = isinstance(radius, np.ndarray)
    if squared is None:
        squared = radius * radius
    over = np.flatnonzero(squares > squared)
    if over.size:
        reach = radius[over] if per_vertex else radius
        scale = (reach / np.sqrt(squares[over])).astype(planar.dtype)
        for k in range(planar.shape[0]):
            planar[k, over] = start[k, over] + away[k, over] * scale


def project_rows_within(points, start, radius):
    """(n, 3) ``points`` projected, in place, onto the balls of ``radius`` (a distance, or one per row)
    around (n, 3) ``start``, in blocks of rows (``project_within`` on each block)."""
    per_vertex = isinstance(radius, np.ndarray)
    for low in range(0, len(points), VECTOR_BLOCK):
        rows = slice(low, low + VECTOR_BLOCK)
        project_within(points[rows].T, start[rows].T, radius[rows] if per_vertex else radius)
