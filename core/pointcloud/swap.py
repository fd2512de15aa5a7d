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

from .geometry import Incidence, _dot, face_normals, incidence_cos, incidence_starts
from .threads import run_blocks

_MIN_GAIN = 1e-9  # radians; ignores swaps that only win by rounding


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
        if other is not None:
            self.other = np.array(other, dtype=np.int64)  # a copy: the passes update it
            low, high = np.asarray(edges, dtype=np.int64).T
            self.keys = low * self.n + high
            return
        inc = Incidence(self.faces, self.n)
        if inc.edge_count.size and inc.edge_count.max() > 2:
            raise ValueError("edge swapping needs a mesh with at most two faces per edge")
        self.other = np.full(3 * self.faces.shape[0], -1, dtype=np.int64)
        two = np.flatnonzero(inc.edge_count == 2)
        i1, i2 = inc.order[inc.edge_start[two]], inc.order[inc.edge_start[two] + 1]
        self.other[i1], self.other[i2] = i2, i1
        self.keys = inc.keys

    @property
    def edges(self):
        return np.stack([self.keys // self.n, self.keys % self.n], axis=1)

    def has_edge(self, u, v):
        keys = np.minimum(u, v) * self.n + np.maximum(u, v)
        if self.keys.size == 0:
            return np.zeros(keys.shape, dtype=bool)
        at = np.minimum(np.searchsorted(self.keys, keys), self.keys.size - 1)
        return self.keys[at] == keys

    def candidates(self, points):
        """Allowed swaps as (i1, i2, a, b, c, d, outer incidences) and the gain of each: i1, i2 the
        incidences of the shared edge ab in faces (a, b, c) and (a, b, d)."""
        faces, other = self.faces, self.other
        i1 = np.flatnonzero(other > np.arange(other.size))  # each interior edge once
        i2 = other[i1]
        f1, j1, f2, j2 = i1 // 3, i1 % 3, i2 // 3, i2 % 3
        a, b, c = faces[f1, (j1 + 1) % 3], faces[f1, (j1 + 2) % 3], faces[f1, j1]
        d = faces[f2, j2]
        usable = (c != d) & ~self.has_edge(c, d)
        i1, i2, f1, j1, f2, j2, a, b, c, d = (x[usable] for x in (i1, i2, f1, j1, f2, j2, a, b, c, d))
        # Outer incidences: in (a, b, c) bc is opposite a, ac opposite b; likewise in (a, b, d).
        f1_oa, f1_ob = 3 * f1 + (j1 + 1) % 3, 3 * f1 + (j1 + 2) % 3
        a_in_f2_next = faces[f2, (j2 + 1) % 3] == a  # slot after d holds a (else b)
        f2_oa = 3 * f2 + np.where(a_in_f2_next, (j2 + 1) % 3, (j2 + 2) % 3)
        f2_ob = 3 * f2 + np.where(a_in_f2_next, (j2 + 2) % 3, (j2 + 1) % 3)
        # Dihedral angles from face normals (see geometry.incidence_cos): today's faces need one
        # normal each, and every candidate only the normals of its two new faces.
        normals = face_normals(points, faces)
        start = incidence_starts(faces)
        gain = np.empty(i1.size)

        def evaluate(lo, hi):
            part = slice(lo, hi)
            pa, pb, pc, pd = (points[x[part]] for x in (a, b, c, d))
            # New faces A = (c, d, a) and B = (c, d, b); their edges start at: A slot 0 (da) d,
            # slot 1 (ac) a; B slot 0 (db) d, slot 1 (bc) b; both slot 2 (cd) c.
            cd = pd - pc
            new_a, new_b = np.cross(cd, pa - pc), np.cross(cd, pb - pc)
            with np.errstate(invalid="ignore", divide="ignore"):
                new_a /= np.sqrt(_dot(new_a, new_a))[:, None]
                new_b /= np.sqrt(_dot(new_b, new_b))[:, None]
            before = np.arccos(np.clip(incidence_cos(normals, faces, i1[part], i2[part], start), -1.0, 1.0))
            after = np.arccos(np.clip(_dot(new_a, new_b), -1.0, 1.0))  # both run c -> d
            for incidence, new, new_start in (
                (f1_oa[part], new_b, b[part]),
                (f1_ob[part], new_a, a[part]),
                (f2_oa[part], new_b, d[part]),
                (f2_ob[part], new_a, d[part]),
            ):
                beyond = other[incidence]
                has = beyond >= 0  # an outer edge without a face beyond counts the same before and after
                far = np.where(has, beyond, incidence)
                before += np.where(
                    has, np.arccos(np.clip(incidence_cos(normals, faces, incidence, far, start), -1, 1)), 0.0
                )
                fb = far // 3
                dot = new[:, 0] * normals[0][fb] + new[:, 1] * normals[1][fb] + new[:, 2] * normals[2][fb]
                cos = np.where(start[far] == new_start, dot, -dot)
                after += np.where(has, np.arccos(np.clip(cos, -1.0, 1.0)), 0.0)
            gain[part] = after - before

        run_blocks(evaluate, i1.size)
        return (i1, i2, a, b, c, d, f1_oa, f1_ob, f2_oa, f2_ob), gain

    def swap_pass(self, points, *, rounds=3):
        """One pass of edge swapping at ``points``; returns the number of swaps."""
        n = self.n
        if self.faces.shape[0] < 2:
            return 0
        (i1, i2, a, b, c, d, f1_oa, f1_ob, f2_oa, f2_ob), gain = self.candidates(points)
        good = np.flatnonzero(np.nan_to_num(gain, nan=-1.0) > _MIN_GAIN)
        vertex_sets = np.stack([a[good], b[good], c[good], d[good]], axis=1)
        priority = np.empty(good.size, dtype=np.int64)
        priority[np.argsort(gain[good], kind="stable")] = np.arange(good.size)  # distinct, by gain
        chosen = np.zeros(good.size, dtype=bool)
        free = np.ones(good.size, dtype=bool)
        used = np.zeros(n, dtype=bool)
        for _ in range(rounds):  # a few greedy rounds over what the winners left free
            if not free.any():
                break
            pick = np.flatnonzero(free)[_independent(vertex_sets[free], priority[free], n)]
            chosen[pick] = True
            used[vertex_sets[pick].ravel()] = True
            free &= ~used[vertex_sets].any(axis=1)
        s = good[chosen]
        if s.size == 0:
            return 0
        self._apply(i1[s], i2[s], a[s], b[s], c[s], d[s], f1_oa[s], f1_ob[s], f2_oa[s], f2_ob[s])
        return int(s.size)

    def _apply(self, i1, i2, a, b, c, d, f1_oa, f1_ob, f2_oa, f2_ob):
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
        gone = np.sort(np.minimum(a, b) * n + np.maximum(a, b))
        keep = np.ones(self.keys.size, dtype=bool)
        keep[np.searchsorted(self.keys, gone)] = False
        kept = self.keys[keep]
        new = np.sort(np.minimum(c, d) * n + np.maximum(c, d))
        self.keys = np.insert(kept, np.searchsorted(kept, new), new)


def swap_pass(points, faces, *, rounds=3):
    """One pass of edge swapping. Returns (new faces, their edges, number of swaps); ``faces`` is
    not modified."""
    swapper = EdgeSwapper(faces, points.shape[0])
    count = swapper.swap_pass(points, rounds=rounds)
    return swapper.faces, swapper.edges, count
