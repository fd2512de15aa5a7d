"""Edge swapping on the RFS mesh (paper section 7, after Freitag et al.), vectorized.

Two faces (a, b, c) and (a, b, d) sharing edge ab become (c, d, a) and (c, d, b) when that increases
the sum of the dihedral angles at the five edges of the pair: the shared edge and the four outer
edges ac, bc, ad, bd (each against the face on its other side; an outer edge without one contributes
the same before and after, so it is left out).

A swap is allowed only when edge cd does not exist yet: then the new faces cannot duplicate a face
and cd gets exactly two faces, while every outer edge keeps its face count, so no edge ever gets
more than two faces.

One pass swaps a set of pairs at once. Chosen pairs touch pairwise disjoint vertex sets: then they
share no face, no two create the same edge, and the face beyond each outer edge (which contains
two vertices of its pair) belongs to no other chosen pair, so every gain was computed on exactly the
mesh the swap is applied to. The set is picked greedily by gain (a Luby-style independent set).

``EdgeSwapper`` keeps the mesh's connectivity between passes (which incidence lies across each
edge, the sorted edge keys) and updates it where swaps happened, so a pass only recomputes the
geometry of the moved points; ``swap_pass`` is one pass on a fresh mesh.
"""

import numpy as np

from .geometry import Incidence, dot_rows, face_normals
from .threads import run_chunks

_MIN_GAIN = 1e-9  # radians; ignores swaps that only win by rounding
_CHUNK = 1 << 16  # elements per step within a thread: its temporaries stay in cache and get reused


def _next(i):
    """The incidence of the next slot in the same face: 3f + (j + 1) % 3 for i = 3f + j."""
    return np.where(i % 3 == 2, i - 2, i + 1)


def _previous(i):
    """3f + (j + 2) % 3 for i = 3f + j."""
    return np.where(i % 3 == 0, i + 2, i - 1)


def _outer(flat, i1, i2, a):
    """The outer incidences of pairs (i1, i2) of faces (a, b, c) and (a, b, d): those opposite a
    and b in the first face, then in the second; and whether a follows d in the second face."""
    after_d, before_d = _next(i2), _previous(i2)
    a_after_d = flat[after_d] == a
    f2_oa = np.where(a_after_d, after_d, before_d)
    f2_ob = np.where(a_after_d, before_d, after_d)
    return _next(i1), _previous(i1), f2_oa, f2_ob, a_after_d


def _unit_cross(u, v):
    """Unit u x v of row vectors (k, 3) as three component arrays (NaN where u, v are parallel)."""
    u0, u1, u2 = u.T
    v0, v1, v2 = v.T
    x = u1 * v2
    x -= u2 * v1
    y = u2 * v0
    y -= u0 * v2
    z = u0 * v1
    z -= u1 * v0
    length = x * x
    length += y * y
    length += z * z
    np.sqrt(length, out=length)
    with np.errstate(invalid="ignore", divide="ignore"):
        x /= length
        y /= length
        z /= length
    return x, y, z


def _angle(cos, same):
    """arccos of cos (in place), negated first where ``same`` is False (None: nowhere)."""
    if same is not None:
        np.negative(cos, out=cos, where=~same)
    return np.arccos(np.clip(cos, -1.0, 1.0, out=cos), out=cos)


def _independent(vertex_sets, priority, n):
    """Candidates whose priority is the highest at each of their vertices (vertex-disjoint)."""
    top = np.full(n, -1, dtype=np.int64)
    for column in vertex_sets.T:
        np.maximum.at(top, column, priority)
    return np.all(top[vertex_sets] == priority[:, None], axis=1)


class EdgeSwapper:
    """A triangle mesh (at most two faces per edge) under repeated swap passes.

    Incidence 3*f + j is the edge of face f opposite its slot j; ``other[i]`` is the incidence on
    the other side of that edge (-1: none); ``keys`` are the sorted edge keys low * n + high.
    """

    def __init__(self, faces, n, other=None, edges=None):
        """``other`` and ``edges`` (an RFSMesh's, for these faces) spare regrouping the incidences."""
        self.n = max(int(n), 1)
        self.faces = np.array(faces, dtype=np.int64).reshape(-1, 3)
        self._normals = None  # the face normals' buffer, reused by every pass
        self._row_start = None  # where each low vertex's run of keys starts (derived from _per_low)
        if other is not None:
            self.other = np.array(other, dtype=np.int64)  # a copy: the passes update it
            low, high = np.asarray(edges, dtype=np.int64).T
            self.keys = low * self.n + high
            self._per_low = np.bincount(low, minlength=self.n)  # keys per low vertex
            return
        inc = Incidence(self.faces, self.n)
        if inc.edge_count.size and inc.edge_count.max() > 2:
            raise ValueError("edge swapping needs a mesh with at most two faces per edge")
        self.other = np.full(3 * self.faces.shape[0], -1, dtype=np.int64)
        two = np.flatnonzero(inc.edge_count == 2)
        i1, i2 = inc.order[inc.edge_start[two]], inc.order[inc.edge_start[two] + 1]
        self.other[i1], self.other[i2] = i2, i1
        self.keys = inc.keys
        self._per_low = np.bincount(inc.edges[:, 0], minlength=self.n)

    @property
    def edges(self):
        return np.stack([self.keys // self.n, self.keys % self.n], axis=1)

    def has_edge(self, u, v):
        low = np.minimum(u, v)
        keys = low * self.n + np.maximum(u, v)
        if self.keys.size == 0:
            return np.zeros(keys.shape, dtype=bool)
        # Binary search within the low vertex's run of keys (a few entries, mostly in one cache
        # line) rather than over all keys.
        row_start = self._key_runs()
        base = row_start[low]
        length = row_start[low + 1] - base
        for _ in range(int(length.max(initial=0)).bit_length()):
            half = length >> 1
            less = self.keys.take(base + half, mode="clip") < keys
            less &= length > 0
            # Go on in the entries after the probe (key greater) or before it.
            base += less * (half + 1)
            length -= less
            length >>= 1
        return self.keys.take(base, mode="clip") == keys  # base: the first entry >= key, or past the run

    def _key_runs(self):
        """Where each low vertex's run of keys starts (n + 1 entries)."""
        if self._row_start is None:
            dtype = np.int32 if self.keys.size < 2**31 else np.int64
            self._row_start = np.zeros(self.n + 1, dtype=dtype)
            np.cumsum(self._per_low, out=self._row_start[1:])
        return self._row_start

    def candidates(self, points):
        """The allowed swaps that gain more than _MIN_GAIN, as (i1, i2, a, b, c, d) with i1, i2 the
        incidences of the shared edge ab in faces (a, b, c) and (a, b, d), and their gains."""
        other = self.other
        flat = self.faces.reshape(-1)  # incidence i's own vertex (the one opposite its edge) is flat[i]
        index = np.int32 if other.size < 2**31 else np.int64
        # Dihedral angles from face normals (see geometry.incidence_cos): today's faces need one
        # normal each, and every candidate only the normals of its two new faces.
        if self._normals is None:
            self._normals = np.empty((self.faces.shape[0], 3))
        normals = face_normals(points, self.faces, out=self._normals)
        self._key_runs()  # before the threads need them

        def chunk(lo, hi):
            # A chunk of incidences does all the work for its interior edges: no full-size
            # temporaries, and only the few winners are kept.
            i1 = np.flatnonzero(other[lo:hi] > np.arange(lo, hi, dtype=index))  # each interior edge once
            i2 = other[lo:hi][i1].astype(index)
            i1 = i1.astype(index)
            i1 += lo
            c, d = flat[i1], flat[i2]
            usable = (c != d) & ~self.has_edge(c, d)
            i1, i2, c, d = i1[usable], i2[usable], c[usable], d[usable]
            gain = self._gain(points, normals, i1, i2, c, d)
            good = gain > _MIN_GAIN  # NaN (a degenerate face) never wins
            return tuple(x[good] for x in (i1, i2, c, d, gain))

        parts = run_chunks(chunk, other.size, _CHUNK)
        i1, i2, c, d, gain = (np.concatenate([part[k] for part in parts]) for k in range(5))
        return (i1, i2, flat[_next(i1)], flat[_previous(i1)], c, d), gain

    def _gain(self, points, normals, i1, i2, c, d):
        """Dihedral angle sum after minus before swapping the faces of each pair (i1, i2)."""
        other = self.other
        flat = self.faces.reshape(-1)
        a, b = flat[_next(i1)], flat[_previous(i1)]
        # Outer incidences: in (a, b, c) bc is opposite a, ac opposite b; likewise in (a, b, d).
        # Both faces run along ab the same way (their edges start at the same vertex) iff a follows d.
        f1_oa, f1_ob, f2_oa, f2_ob, a_after_d = _outer(flat, i1, i2, a)
        # New faces A = (c, d, a) and B = (c, d, b); their edges start at: A slot 0 (da) d,
        # slot 1 (ac) a; B slot 0 (db) d, slot 1 (bc) b; both slot 2 (cd) c.
        pc = points[c]
        cd = points[d] - pc
        new_a, new_b = _unit_cross(cd, points[a] - pc), _unit_cross(cd, points[b] - pc)
        own_1, own_2 = normals[i1 // 3], normals[i2 // 3]
        before = _angle(dot_rows(own_1, own_2), a_after_d)
        after = _angle(new_a[0] * new_b[0] + new_a[1] * new_b[1] + new_a[2] * new_b[2], None)  # both c -> d
        for incidence, own, new, new_start in (
            (f1_oa, own_1, new_b, b),
            (f1_ob, own_1, new_a, a),
            (f2_oa, own_2, new_b, d),
            (f2_ob, own_2, new_a, d),
        ):
            beyond = other[incidence]
            # -1 (no face beyond) indexes a valid row and slot; those terms are dropped below.
            normal = normals[beyond // 3]
            beyond_start = flat[_next(beyond)]  # where the edge starts in each face (incidence_starts)
            term = _angle(dot_rows(own, normal), flat[_next(incidence)] == beyond_start)
            term[beyond < 0] = 0.0  # an outer edge without a face beyond counts the same before and after
            before += term
            term = _angle(
                new[0] * normal[:, 0] + new[1] * normal[:, 1] + new[2] * normal[:, 2], beyond_start == new_start
            )
            term[beyond < 0] = 0.0
            after += term
        after -= before
        return after

    def swap_pass(self, points, *, rounds=3):
        """One pass of edge swapping at ``points``; returns the number of swaps."""
        n = self.n
        if self.faces.shape[0] < 2:
            return 0
        (i1, i2, a, b, c, d), gain = self.candidates(points)
        vertex_sets = np.stack([a, b, c, d], axis=1)
        priority = np.empty(gain.size, dtype=np.int64)
        priority[np.argsort(gain, kind="stable")] = np.arange(gain.size)  # distinct, by gain
        chosen = np.zeros(gain.size, dtype=bool)
        free = np.ones(gain.size, dtype=bool)
        used = np.zeros(n, dtype=bool)
        for _ in range(rounds):  # a few greedy rounds over what the winners left free
            if not free.any():
                break
            pick = np.flatnonzero(free)[_independent(vertex_sets[free], priority[free], n)]
            chosen[pick] = True
            used[vertex_sets[pick].ravel()] = True
            free &= ~used[vertex_sets].any(axis=1)
        s = np.flatnonzero(chosen)
        if s.size == 0:
            return 0
        self._apply(i1[s], i2[s], a[s], b[s], c[s], d[s])
        return int(s.size)

    def _apply(self, i1, i2, a, b, c, d):
        f1_oa, f1_ob, f2_oa, f2_ob, _ = _outer(self.faces.reshape(-1), i1, i2, a)
        f1, f2 = i1 // 3, i2 // 3
        other = self.other
        # Faces beyond the four outer edges, read before anything is rewritten.
        beyond = [other[x] for x in (f2_ob, f1_ob, f2_oa, f1_oa)]
        self.faces[f1] = np.stack([c, d, a], axis=1)  # slot 0: edge da, 1: ac, 2: cd
        self.faces[f2] = np.stack([c, d, b], axis=1)  # slot 0: edge db, 1: bc, 2: cd
        for mine, far in zip((3 * f1, 3 * f1 + 1, 3 * f2, 3 * f2 + 1), beyond):
            other[mine] = far
            has = far >= 0
            other[far[has]] = mine[has]
        other[3 * f1 + 2], other[3 * f2 + 2] = 3 * f2 + 2, 3 * f1 + 2
        # Edge keys: every swap trades its ab for cd (both sorted lists, merged).
        n = self.n
        np.subtract.at(self._per_low, np.minimum(a, b), 1)
        np.add.at(self._per_low, np.minimum(c, d), 1)
        self._row_start = None
        gone = np.sort(np.minimum(a, b) * n + np.maximum(a, b))
        new = np.sort(np.minimum(c, d) * n + np.maximum(c, d))
        self.keys = _replaced(self.keys, gone, new)


def _replaced(keys, gone, new):
    """The sorted keys without the sorted keys ``gone`` (all present) and with the sorted keys ``new``
    (all absent)."""
    keep = np.ones(keys.size, dtype=bool)
    keep[np.searchsorted(keys, gone)] = False
    kept = keys[keep]
    return np.insert(kept, np.searchsorted(kept, new), new)


def swap_pass(points, faces, *, rounds=3):
    """One pass of edge swapping. Returns (new faces, their edges, number of swaps); ``faces`` is
    not modified.

    Examples
    --------
    Two triangles folded along their long shared edge 0-1: the swap makes 2-3 the shared edge.

    >>> import numpy as np, core
    >>> points = np.array([[0, 0, 0], [2, 0, 0], [1, 0.5, 0.3], [1, -0.5, 0.3]])
    >>> faces, edges, swaps = core.pointcloud.swap_pass(points, np.array([[0, 1, 2], [1, 0, 3]]))
    >>> faces.tolist(), swaps
    ([[2, 3, 0], [2, 3, 1]], 1)
    """
    swapper = EdgeSwapper(faces, points.shape[0])
    count = swapper.swap_pass(points, rounds=rounds)
    return swapper.faces, swapper.edges, count
