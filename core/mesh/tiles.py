"""Smoothing a mesh in spatial tiles: the mathematics of scans larger than memory (files: cli/tiled.py).

**Locality.** A simultaneous HC iteration reads two rings (p_i needs b_j of its neighbours, b_j needs
q of theirs); a Laplacian iteration reads one. So after k iterations a vertex's result depends only on
the input within ``tile_rings`` rings: 2k for HC, k for the Laplacian variants, one more for each pass
that reads the result's normals (Keep in Place's projection, the normals a file stores) and
``in_place._LAST`` more for Keep in Place's fold guard, whose rounds each reach one ring further.

**Tiles.** A path of r edges is at most r times the longest edge long, so every vertex within r rings of
a box lies within ``margin`` = r x the longest edge of it, in every coordinate. A tile is a box of space
(its *own* vertices) with its *halo*: every vertex within the margin, and the faces whose corners all
lie there. A vertex of the halo has its whole 1-ring (and every face around it) in the tile when it lies
one ring further in than the tile's edge, so every own vertex sees exactly the rows it would see in the
whole mesh. Smoothed with its vertices in their order in the whole mesh, each row's neighbours are
summed in the same order: the own vertices' results are the whole run's, bit for bit (except where the
whole run would renumber a scattered mesh for cache locality, core.locality: then to rounding).

The boxes cut space where the vertices are (``tile_boxes``): a k-d split of an even sample of the vertices,
each box cut at the median along its longest side until its tile (box and halo) holds at most the
vertices a tile may hold.

What needs a whole part at once cannot run tiled as it is: the Automatic Amount's choice (made once, on
a region, and run on every tile with the numbers it chose), the volume restore of closed parts (its sums
gathered tile by tile: core.mesh.tile_volume), the parts it holds or gives back (core.mesh.collapse),
Keep Sharp Edges, Gauss-Seidel order and an early stop on the largest move (``tiled_problem``).
"""

from dataclasses import dataclass, replace

import numpy as np

from ..slices import to_end
from .amount import AmountChooser, most_iterations
from .in_place import _LAST as UNFOLD_ROUNDS
from .smooth import AUTO, DEVIATION_IN_NOISE, MeshSmoother
from .welding import TOLERANCE as WELD_TOLERANCE

MOST_TILES = 4096  # more boxes than this: the halo is most of every tile (``tile_boxes`` refuses)
_SLACK = 1e-9  # relative: the margin covers the rounding of the lengths it is made of


def tile_rings(method, iterations, keep_in_place=False, normals=False, volume=False):
    """The rings around a vertex that its result reads (see the module docstring): the halo a tile needs.
    ``normals``: the result's vertex normals are written too; ``volume``: the tile adds its sums for the
    volume restore (core.mesh.tile_volume), whose triangles' corners lie a ring out and read the normals
    there: two rings more (its normals are written by the restore's own pass).

    Examples
    --------
    >>> import core
    >>> core.tile_rings("hc", 10), core.tile_rings("plain", 10), core.tile_rings("hc", 10, normals=True)
    (20, 10, 21)
    >>> core.tile_rings("hc", 10, normals=True, volume=True)
    22
    """
    rings = (2 if method == "hc" else 1) * int(iterations)
    if keep_in_place:
        rings += 1 + UNFOLD_ROUNDS
    return rings + (2 if volume else 1 if normals else 0)


def tile_margin(rings, longest_edge):
    """How far (in every coordinate) beyond its box a tile reaches so that it holds every vertex within
    ``rings`` rings of its own: welded copies (core.mesh.welding) may lie the welding tolerance apart, so
    each ring is taken that much longer.

    Examples
    --------
    >>> import core
    >>> round(core.tile_margin(20, 0.5), 6)  # 20 rings of edges at most 0.5 long, each 1e-6 longer
    10.00001
    """
    return rings * longest_edge * (1.0 + WELD_TOLERANCE) * (1.0 + _SLACK) + _SLACK * longest_edge


@dataclass(frozen=True)
class Box:
    """An axis-aligned box of space: a point p is its own where low <= p < high in every coordinate,
    p <= high where ``closed`` (the boxes' outer sides), so the boxes of ``tile_boxes`` own every point once."""

    low: np.ndarray
    high: np.ndarray
    closed: np.ndarray  # (3,) bool

    def owns(self, points):
        """(m,) bool: the points of (m, 3) ``points`` this box owns."""
        points = np.asarray(points)
        inside = np.ones(len(points), dtype=bool)
        for axis in range(3):
            values = points[:, axis]
            inside &= values >= self.low[axis]
            inside &= values <= self.high[axis] if self.closed[axis] else values < self.high[axis]
        return inside

    def reaches(self, points, margin):
        """(m,) bool: the points within ``margin`` of this box in every coordinate (its tile)."""
        points = np.asarray(points)
        inside = np.ones(len(points), dtype=bool)
        for axis in range(3):
            values = points[:, axis]
            inside &= (values >= self.low[axis] - margin) & (values <= self.high[axis] + margin)
        return inside

    def cut(self, axis, value):
        """(lower, upper) halves at ``value`` along ``axis``: the lower half owns what lies below it."""
        high, low = self.high.copy(), self.low.copy()
        high[axis] = low[axis] = value
        closed = self.closed.copy()
        closed[axis] = False
        return Box(self.low, high, closed), Box(low, self.high, self.closed)


def tile_boxes(sample, scale, low, high, margin, most):
    """Boxes (``Box``) owning every point between ``low`` and ``high`` once, each of whose tiles (the box
    and ``margin`` around it) holds about ``most`` vertices at most.

    ``sample``: (m, 3) an even sample of the vertices, each standing for ``scale`` of them. A box is cut
    at the median of its own sample points along its longest side while its tile holds too many; raises
    ValueError where the box is narrower than half the margin and its tile still holds too many (the halo
    alone does).

    Examples
    --------
    >>> import numpy as np, core
    >>> points = np.random.default_rng(0).uniform(size=(10_000, 3))
    >>> boxes = core.tile_boxes(points, 1.0, [0, 0, 0], [1, 1, 1], 0.02, 3_000)
    >>> len(boxes), max(int(box.reaches(points, 0.02).sum()) for box in boxes) <= 3_000
    (4, True)
    >>> int(sum(box.owns(points) for box in boxes).max())  # every point has one box
    1
    """
    sample = np.asarray(sample, dtype=np.float64)
    whole = Box(np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64), np.ones(3, dtype=bool))
    done, todo = [], [whole]
    while todo:
        box = todo.pop()
        if box.reaches(sample, margin).sum() * scale <= most:
            done.append(box)
            continue
        if len(done) + len(todo) + 2 > MOST_TILES:
            raise ValueError(f"more than {MOST_TILES} tiles")
        own = sample[box.owns(sample)]
        axis = int(np.argmax(box.high - box.low))
        value = float(np.median(own[:, axis])) if len(own) else 0.5 * (box.low[axis] + box.high[axis])
        if not box.low[axis] < value < box.high[axis]:
            value = 0.5 * (box.low[axis] + box.high[axis])
        if box.high[axis] - box.low[axis] < 0.5 * margin:  # a box narrower than its halo: cuts no longer help
            raise ValueError(
                f"a tile's halo alone holds about {box.reaches(sample, margin).sum() * scale:.0f} vertices, more "
                f"than the {most:.0f} a tile may hold"
            )
        halves = box.cut(axis, value)
        todo.extend(halves)
    return done


def tiles_choose(options):
    """Whether core.MeshSmoother ``options`` leave the amount to the Automatic Amount (as MeshSmoother reads
    them): then a tiled run chooses it once (``region_amount``).

    Examples
    --------
    >>> import core
    >>> core.tiles_choose({}), core.tiles_choose({"iterations": 10}), core.tiles_choose({"method": "plain"})
    (True, False, False)
    """
    hc = options.get("method", "hc") == "hc" or options.get("keep_sharp_edges", False)
    return hc and options.get("alpha", AUTO) == AUTO and options.get("iterations", AUTO) == AUTO


def tiled_problem(options, tiled_words="in tiles"):
    """What in core.MeshSmoother ``options`` cannot run tiled, as a sentence, or None.

    Examples
    --------
    >>> import core
    >>> core.tiled_problem({"iterations": 10}) is None
    True
    >>> core.tiled_problem({"keep_sharp_edges": True})
    'Keep Sharp Edges cannot run in tiles: its filter of face normals needs whole parts'
    """
    if options.get("keep_sharp_edges"):
        return f"Keep Sharp Edges cannot run {tiled_words}: its filter of face normals needs whole parts"
    if options.get("mode", "simultaneous") != "simultaneous":
        return (
            f"the sequential mode cannot run {tiled_words}: each vertex reads the new positions of all lower "
            "numbered ones, which may lie anywhere"
        )
    if options.get("tolerance", 0.0):
        return f"--tolerance cannot run {tiled_words}: its stop reads the largest move of the whole mesh"
    return None


@dataclass(frozen=True)
class TileAmount:
    """What the Automatic Amount chose on a region, for every tile: ``options`` are core.MeshSmoother's
    with the numbers set (alpha, beta, iterations, the deviation limit, Keep in Place on or off), so each
    tile runs the paper's algorithm with them; ``amount`` the core.MeshAmount; ``region`` its vertices."""

    options: dict
    amount: object
    region: int
    limit: float


def region_amount(positions, edges, triangles, options, total_vertices):
    """The Automatic Amount chosen once on a region of a big mesh (``positions``, ``edges``, ``triangles``,
    its vertices in the mesh's order) for a run on every tile of it: the region is prepared as the whole
    mesh would be (welded, the border rule), core.AmountChooser chooses on it (on patches, as on any big
    mesh), and the iterations are cut to the work budget of the whole mesh's ``total_vertices``, as a
    whole run cuts them. The deviation limit is DEVIATION_IN_NOISE times the noise found, or where the
    region's largest part is quiet or lightly noisy that part's own radius (core.mesh.noise). Returns a
    TileAmount.

    Examples
    --------
    >>> import numpy as np, core
    >>> u, v = np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20))
    >>> noisy = np.c_[u.ravel(), v.ravel(), np.random.default_rng(0).normal(scale=0.01, size=400)]
    >>> grid = np.arange(400).reshape(20, 20)[:-1, :-1].ravel()
    >>> triangles = np.concatenate([np.c_[grid, grid + 1, grid + 21], np.c_[grid, grid + 21, grid + 20]])
    >>> edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    >>> chosen = core.region_amount(noisy, edges, triangles, {}, total_vertices=10_000_000)
    >>> chosen.amount.iterations, chosen.options["alpha"], chosen.options["keep_in_place"]  # 60M / 10M
    (6, 0.0, True)
    """
    run = MeshSmoother(positions, edges, faces=triangles, **options)
    if not run.automatic:
        raise ValueError("region_amount is for runs with the Automatic Amount (alpha and iterations 'auto')")
    run.still()  # welds, finds the surface and applies the border rule, as a whole run begins
    chooser = AmountChooser(run.positions, operator=run.surface_operator, beta=run.beta, fixed=run.fixed)
    if run.beta_given:
        chooser.fine_beta = None
    to_end(chooser.steps())
    amount, noise = chooser.amount, chooser.noise
    iterations = min(amount.iterations, most_iterations(total_vertices))
    capped = amount.capped or iterations < amount.iterations
    amount = replace(amount, iterations=iterations, capped=capped)
    limit = options.get("max_deviation", AUTO)
    if limit == AUTO:
        largest = int(np.argmax(np.bincount(noise.part_of_vertex)))
        limit = DEVIATION_IN_NOISE * amount.sigma
        if noise.limited[noise.part_of_vertex == largest].any():
            radius = noise.quiet_radius(run.positions, DEVIATION_IN_NOISE)
            limit = float(radius[noise.part_of_vertex == largest][0])
        if noise.held()[noise.part_of_vertex == largest].all():
            iterations = 0  # no noise on a clean shape: nothing moves, as a whole run holds it
    keep = options.get("keep_in_place", AUTO)
    chosen = {
        **options,
        "alpha": amount.alpha,
        "beta": amount.beta,
        "iterations": iterations,
        "max_deviation": float(limit),
        "keep_in_place": run.in_place if keep == AUTO else bool(keep),
    }
    return TileAmount(chosen, replace(amount, iterations=iterations), len(run.positions), float(limit))
