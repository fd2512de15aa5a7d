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
"""

import numpy as np

from .geometry import Incidence, angle_between, dihedral, perpendicular

_MIN_GAIN = 1e-9  # radians; ignores swaps that only win by rounding


def _swap_candidates(points, faces, inc):
    """Interior edges whose swap is allowed, as (edge, f1, f2, a, b, c, d), and the gain of each."""
    interior = np.flatnonzero(inc.edge_count == 2)
    i1 = inc.order[inc.edge_start[interior]]
    i2 = inc.order[inc.edge_start[interior] + 1]
    a, b = inc.edges[interior, 0], inc.edges[interior, 1]
    c, d = inc.third[i1], inc.third[i2]
    # Per incidence (face, edge) the unit vector from the edge into the face: dihedral angles of
    # today's mesh are angles between two of these, so the "before" sums need no new geometry.
    f = inc.faces
    w = perpendicular(points, f[:, [1, 2, 0]].ravel(), f[:, [2, 0, 1]].ravel(), f.ravel())
    # For each incidence the incidence on the other side of its edge (-1: none).
    other = np.full(inc.third.size, -1, dtype=np.int64)
    other[i1], other[i2] = i2, i1

    usable = ~inc.has_edge(c, d) & (c != d)
    edge, i1, i2, a, b, c, d = (x[usable] for x in (interior, i1, i2, a, b, c, d))
    f1, f2 = i1 // 3, i2 // 3

    def outer(face, opposite):
        # The edge of ``face`` opposite vertex ``opposite`` is incidence 3*face + its slot.
        slot = np.argmax(faces[face] == opposite[:, None], axis=1)
        return 3 * face + slot

    before = angle_between(w[i1], w[i2])
    after = dihedral(points, c, d, a, b)
    # Outer edges: bc and ac of (a, b, c) get d as their new third vertex, bd and ad of (a, b, d) get c.
    for incidence, u, v, new in ((outer(f1, a), b, c, d), (outer(f1, b), a, c, d),
                                 (outer(f2, a), b, d, c), (outer(f2, b), a, d, c)):
        beyond = other[incidence]
        has = beyond >= 0  # an outer edge without a face beyond counts the same before and after: skip
        before[has] += angle_between(w[incidence[has]], w[beyond[has]])
        after[has] += angle_between(perpendicular(points, u[has], v[has], new[has]), w[beyond[has]])
    return edge, f1, f2, a, b, c, d, after - before


def _independent(vertex_sets, priority, n):
    """Candidates whose priority is the highest at each of their vertices (vertex-disjoint)."""
    top = np.full(n, -1, dtype=np.int64)
    for column in vertex_sets.T:
        np.maximum.at(top, column, priority)
    return np.all(top[vertex_sets] == priority[:, None], axis=1)


def swap_pass(points, faces, *, rounds=3):
    """One pass of edge swapping. Returns (new faces, their edges, number of swaps); ``faces`` is
    not modified."""
    n = points.shape[0]
    faces = faces.astype(np.int64, copy=True)
    inc = Incidence(faces, max(n, 1))
    if faces.shape[0] < 2:
        return faces, inc.edges, 0
    edge, f1, f2, a, b, c, d, gain = _swap_candidates(points, faces, inc)
    good = np.flatnonzero(np.nan_to_num(gain, nan=-1.0) > _MIN_GAIN)
    vertex_sets = np.stack([a, b, c, d], axis=1)[good]
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
    faces[f1[s]] = np.stack([c[s], d[s], a[s]], axis=1)
    faces[f2[s]] = np.stack([c[s], d[s], b[s]], axis=1)
    # Edges: every swap trades its ab for cd.
    keep = np.ones(inc.edges.shape[0], dtype=bool)
    keep[edge[s]] = False
    new_edges = np.stack([np.minimum(c[s], d[s]), np.maximum(c[s], d[s])], axis=1)
    return faces, np.concatenate([inc.edges[keep], new_edges]), int(s.size)
