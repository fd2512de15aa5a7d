"""Scans larger than memory: a binary PLY or an OBJ file smoothed in spatial tiles (core.tile_boxes), read
and written in blocks (cli/formats/ply_blocks.py, cli/formats/obj_blocks.py). No Blender here: NumPy, SciPy
and core. STL is refused (``STL_REFUSAL``).

The route, for a file whose whole run would not fit in the memory limit (``needs_tiles``):

0. An OBJ file is indexed first: one pass over its text writes its positions and faces into scratch files
   beside the target, which the passes below read as they read a binary PLY's records.
1. One pass over the vertices (bounds, an even sample, finite coordinates) and one over the faces (their
   corners checked, the longest edge).
2. With the Automatic Amount, the amount is chosen once, on a region of about REGION_VERTICES vertices
   around REGION_PLACES places spread over the file (core.region_amount), and every tile runs the
   numbers it chose.
3. The boxes (core.tile_boxes), each tile holding what the run reads (core.tile_rings rings of
   halo), at most as many vertices as the limit leaves room for.
4. The input is copied to a hidden temporary file beside the target; each tile is read (a pass over the
   vertices, one over the faces), smoothed with its vertices in the file's order, and its own vertices'
   positions (and the normals the file stores per vertex) written into the copy in place; the copy replaces
   the target only once every tile is written (cli/files.py), so an interrupt or a failure leaves no output.
   Each tile is a ``TileJob`` that writes only its own rows: on a Dask worker the tiles go to the cluster's
   workers (``runner``, cli/batch.py), in any order, with the same bytes.
   An OBJ's tiles write into a scratch copy of its positions instead; a last pass writes the output text
   (obj_blocks.ObjOutput), its `vn` normals recomputed from the whole result.
5. With the Automatic Amount, closed parts get their volume back (core.TiledVolume): the tiles of step 4
   add their sums and keep their results in a scratch copy (``SmoothedCopy``) instead; the offsets are
   solved once, and a second pass over the tiles moves their vertices and writes them (``restore_tiles``).

Memory: a tile's run, plus one index per vertex (4 bytes; 8 beyond 2**31 vertices) to number a tile's
vertices (and one for the parts, with the volume restore) and a sample of at most SAMPLE_POINTS positions.
Reading goes through the page cache, not through arrays of the whole file.
"""

import contextlib
import os
import time
from dataclasses import dataclass, field

import numpy as np

from .. import core
from . import files
from .formats import normals as normal_maths
from .formats.obj_blocks import ObjBlocks
from .formats.ply_blocks import PlyBlocks
from .formats.tokens import FormatError

# What a whole (in-core) run of the command line takes per vertex, file included, at most (measured:
# bench/bench_tiled.py): a file whose vertices need more than the limit goes in tiles.
IN_CORE_BYTES_PER_VERTEX = 800
# What a tile's run takes per vertex of the tile, its faces and buffers included (measured, as above).
TILE_BYTES_PER_VERTEX = 600
BASE_BYTES = 320 << 20  # the interpreter, NumPy, SciPy (and Blender's module) and the blocks being read
MEMORY_SHARE = 0.75  # the default limit: this share of the machine's memory
BLOCK = 1 << 20  # records per block read
SAMPLE_POINTS = 1 << 20  # vertices sampled for the boxes
REGION_VERTICES = 1_000_000  # about this many vertices for the Automatic Amount's choice ...
REGION_PLACES = 8  # ... in boxes around this many places spread over the file's vertices
SMALLEST_TILE = 10_000  # a limit leaving room for fewer vertices per tile is refused
PIECE_SHARE = 0.1  # of the limit, the most the volume restore's sums per piece of a part may take (core.TiledVolume)


def default_memory_limit():
    """MEMORY_SHARE of the machine's physical memory (bytes); 8 GB where it cannot be read."""
    try:
        return int(MEMORY_SHARE * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 8 << 30


def size_words(count):
    """'4.0 GB', '512 MB'."""
    return f"{count / (1 << 30):.1f} GB" if count >= 1 << 30 else f"{count / (1 << 20):.0f} MB"


def in_core_bytes(vertices):
    return BASE_BYTES + IN_CORE_BYTES_PER_VERTEX * vertices


def estimated_vertices(path):
    """The vertices of the mesh file ``path`` as far as can be told before reading it: a PLY header's count,
    else (OBJ, STL, a PLY header that cannot be read) one per 12 bytes of the file (its least), 0 when
    there is no file."""
    if not os.path.isfile(path):
        return 0
    if os.path.splitext(path)[1].lower() == ".ply":
        try:
            from .formats.ply import parse_header
            from .formats.ply_blocks import read_header

            _, elements, _ = parse_header(read_header(path))
            return next((element.count for element in elements if element.name == "vertex"), 0)
        except (FormatError, OSError):
            pass
    return os.path.getsize(path) // 12


def needs_tiles(path, limit):
    """Whether smoothing the mesh file ``path`` whole would take more than ``limit`` bytes."""
    return in_core_bytes(estimated_vertices(path)) > limit


def surface_arrays(corners, sizes):
    """(edges, triangles) of faces given as ``corners`` (vertex indices, face after face) with ``sizes``: the
    sides and fan triangles of the faces Blender would keep (at least three corners, none repeating the one
    before it), face after face. The one rule of the file routes (command.mesh_job uses it too)."""
    if len(sizes) and sizes[0] >= 3 and corners.size == sizes[0] * len(sizes) and np.all(sizes == sizes[0]):
        return _alike_surface(corners.reshape(len(sizes), -1))
    starts = np.cumsum(sizes) - sizes
    following, _ = normal_maths.corner_neighbours(starts, sizes)
    degenerate = np.repeat(np.arange(len(sizes)), sizes)[corners == corners[following]]
    keep = sizes >= 3
    keep[degenerate] = False
    mask = np.repeat(keep, sizes)
    edges = np.stack([corners[mask], corners[following][mask]], axis=1)
    kept = sizes[keep]
    triangles = core.fan_triangles((np.concatenate([[0], np.cumsum(kept)]), corners[mask]))
    return edges, triangles


def _alike_surface(grid):
    """``surface_arrays`` of (f, k) faces all of k >= 3 corners, column by column."""
    k = grid.shape[1]
    degenerate = np.zeros(len(grid), dtype=bool)
    for column in range(k):
        degenerate |= grid[:, column] == grid[:, (column + 1) % k]
    kept = grid[~degenerate] if degenerate.any() else grid
    edges = np.empty((kept.size, 2), dtype=kept.dtype)
    edges[:, 0] = kept.ravel()
    edges[:, 1] = np.roll(kept, -1, axis=1).ravel()
    return edges, core.fan_triangles(kept)


@dataclass
class Scan:
    """The first passes' findings: bounds, the longest edge, an even sample of the vertices."""

    low: np.ndarray
    high: np.ndarray
    longest_edge: float
    sample: np.ndarray
    sample_indices: np.ndarray

    @property
    def diagonal(self):
        return float(np.linalg.norm(self.high - self.low))


@dataclass
class TiledRun:
    """What a tiled run did: the counts the command line reports and the sentences it says."""

    vertices: int = 0
    limit: int = 0  # bytes
    tiles: int = 0
    iterations: int = 0
    largest_tile: int = 0
    margin: float = 0.0
    rings: int = 0
    amount: object = None  # core.MeshAmount chosen on a region (Automatic Amount), else None
    change: object = None  # core.Change from the tiles' sums (the volume where the restore's pass measured it)
    notes: list = field(default_factory=list)
    kept_in_place: bool = False
    options: dict = field(default_factory=dict)  # core.MeshSmoother's options every tile ran
    restoring: bool = False  # the closed parts' volume given back (core.TiledVolume): the Automatic Amount's
    volume_offset: float = 0.0  # the largest offset that gave a closed part its volume back


def blocks(count, size=BLOCK):
    return ((start, min(start + size, count)) for start in range(0, count, size))


def scan(mesh):
    """One pass over the vertices and one over the faces (``Scan``); raises FormatError for a coordinate that
    is not finite or a face that names a vertex the file does not have."""
    n = mesh.vertex_count
    stride = max(1, -(-n // SAMPLE_POINTS))
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    sample, picked = [], []
    for start, stop in blocks(n):
        points = mesh.positions(start, stop)
        bad = ~np.isfinite(points).all(axis=1)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise FormatError(
                f"vertex {start + row} has a coordinate that is not a finite number ({points[row]}); nothing was "
                "written"
            )
        low, high = np.minimum(low, points.min(axis=0)), np.maximum(high, points.max(axis=0))
        first = -start % stride
        sample.append(points[first::stride].astype(np.float64))
        picked.append(np.arange(start + first, stop, stride))
    longest = 0.0
    for start, stop in blocks(mesh.face_count):
        corners = mesh.faces(start, stop)
        squares = np.zeros(corners.shape)
        # strided views of a map made for this block: a gather reads only the coordinates, and only this
        # block's pages stay resident
        for column in mesh.coordinates():
            at = column[corners].astype(np.float64)
            squares += (at - np.roll(at, -1, axis=1)) ** 2
        if squares.size:
            longest = max(longest, float(np.sqrt(squares.max())))
    return Scan(low, high, longest, np.concatenate(sample), np.concatenate(picked))


@dataclass
class Tile:
    """A tile read from the file: its vertices (indices in the file, increasing), their positions, which are
    the box's own, and its faces' corners numbered in the tile."""

    vertices: np.ndarray
    positions: np.ndarray
    own: np.ndarray
    corners: np.ndarray


def read_tile(mesh, reaches, owns, lookup):
    """The Tile of the vertices ``reaches(points)`` selects (``owns(points)`` its own), with the faces whose
    corners all lie among them. ``lookup`` ((n,) -1 everywhere) numbers them meanwhile and is reset."""
    vertices, positions, own = [], [], []
    for start, stop in blocks(mesh.vertex_count):
        points = mesh.positions(start, stop)
        inside = np.flatnonzero(reaches(points))
        vertices.append(start + inside)
        positions.append(points[inside])
        own.append(owns(points[inside]))
    vertices = np.concatenate(vertices)
    lookup[vertices] = np.arange(len(vertices), dtype=lookup.dtype)
    try:
        corners = []
        for start, stop in blocks(mesh.face_count):
            local = lookup[mesh.faces(start, stop)]
            inside = local[:, 0] >= 0
            for column in range(1, local.shape[1]):
                inside &= local[:, column] >= 0
            corners.append(local[inside])
    finally:
        lookup[vertices] = -1
    return Tile(vertices, np.concatenate(positions), np.concatenate(own), np.concatenate(corners).astype(np.int64))


def tile_capacity(limit, n, parts=False, spread=False):
    """The vertices a tile may hold within ``limit`` bytes, beside the per-vertex lookup and the sample (and
    with ``parts`` the volume restore's index of the parts, core.TiledVolume; with ``spread``, tiles run by
    workers, each tile's own lookup beside the file's, which a worker may hold too)."""
    lookups = 1 + int(parts) + int(spread)
    spare = limit - BASE_BYTES - lookups * np.dtype(index_dtype(n)).itemsize * n - 24 * min(n, SAMPLE_POINTS)
    return int(spare // TILE_BYTES_PER_VERTEX)


def index_dtype(n):
    return np.int32 if n < np.iinfo(np.int32).max else np.int64


STL_REFUSAL = (
    "an STL file is a triangle soup: its vertices are made by welding equal corners across the whole file, which "
    "tiles cannot do; STL files are smoothed whole (raise --memory-limit)"
)


@contextlib.contextmanager
def mesh_blocks(source, temporary):
    """The mesh file ``source`` read in blocks: PlyBlocks (binary PLY), ObjBlocks (OBJ, indexed into scratch files
    beside ``temporary`` and removed afterwards); raises FormatError for any other file."""
    ext = os.path.splitext(source)[1].lower()
    if ext == ".ply":
        yield PlyBlocks(source)
    elif ext == ".obj":
        with ObjBlocks(source, lambda: files.temporary_path(temporary) + ".tmp") as obj:
            yield obj
    elif ext == ".stl":
        raise FormatError(STL_REFUSAL)
    else:
        raise FormatError(f"a {ext or 'file without extension'} file cannot be smoothed in tiles (PLY or OBJ)")


def smooth_file(source, target, options, limit, say=None, capacity=None, runner=None):
    """Smooth the binary PLY or OBJ ``source`` into ``target`` in tiles within about ``limit`` bytes; ``options``
    are core.MeshSmoother's (the operators' core_options): where they leave alpha and iterations to the
    Automatic Amount, it chooses them once (``choose_on_region``). ``say(text)`` hears each tile's progress;
    ``capacity``: the vertices a tile may hold (default: what ``limit`` leaves room for). ``runner``: where the
    smoothing pass's tiles run, ``runner(jobs)`` yielding each ``TileJob``'s ``TileDone`` as it finishes (in any
    order: each tile writes only its own rows), e.g. on a Dask cluster's workers (cli/batch.py); None: here, one
    after the other. Returns a TiledRun; raises FormatError or ValueError with a message for what cannot run
    tiled (nothing is written then)."""
    say = say or (lambda text: None)
    problem = core.tiled_problem(options)
    if problem:
        raise ValueError(f"{problem}; smooth it whole (a larger --memory-limit) or leave the option out")
    started = time.perf_counter()
    with files.written(target) as temporary, mesh_blocks(source, temporary) as mesh:
        n = mesh.vertex_count
        if capacity is None and tile_capacity(limit, n) < min(SMALLEST_TILE, n):
            raise ValueError(
                f"--memory-limit {size_words(limit)} leaves no room for a tile of this scan's {n} vertices "
                f"(at least {size_words(BASE_BYTES + SMALLEST_TILE * TILE_BYTES_PER_VERTEX + 4 * n)})"
            )
        run = TiledRun(vertices=n, limit=limit)
        restoring = core.tiles_choose(options)  # the Automatic Amount gives closed parts their volume back
        if restoring and capacity is None and tile_capacity(limit, n, parts=True) < min(SMALLEST_TILE, n):
            restoring = False
            run.notes.append(
                f"the parts of the whole mesh ({np.dtype(index_dtype(n)).itemsize} bytes a vertex) leave no room "
                f"for a tile within --memory-limit {size_words(limit)}: no closed part gets its volume back "
                "(raise --memory-limit)"
            )
        capacity = capacity or tile_capacity(limit, n, parts=restoring, spread=runner is not None)
        found = scan(mesh)
        lookup = np.full(n, -1, dtype=index_dtype(n))
        boxes = plan_tiles(mesh, found, options, lookup, capacity, limit, run, restoring)
        options = run.options
        totals = Totals()
        output = mesh.output(temporary)
        with smoothed_copy(temporary, n, run.restoring) as smoothed:
            volume = tiled_volume(run, found, options) if run.restoring else None
            centre = None if volume is None else volume.centre
            jobs = [TileJob(mesh, output, smoothed, box, run.margin, options, centre) for box in boxes]
            done = (run_tile(job, lookup) for job in jobs) if runner is None else runner(jobs)
            for number, tile in enumerate(done, 1):
                run.largest_tile = max(run.largest_tile, tile.vertices)
                totals.merge(tile.totals)
                if volume is not None:
                    volume.add(tile.piece)
                words = f"{tile.vertices} vertices, {tile.own} its own, {tile.seconds:.1f} s"
                say(f"tile {number} of {len(boxes)}: {words}")
            if volume is not None:
                restore_tiles(mesh, found, options, boxes, lookup, volume, smoothed, output, totals, run, say)
        output.finish()
    run.change = totals.change(found)
    run.notes.insert(
        0,
        f"smoothed in {run.tiles} tiles of at most {run.largest_tile} vertices ({run.rings} rings of halo, "
        f"{run.margin:.3g} around each box), {time.perf_counter() - started:.1f} s",
    )
    return run


def tiled_volume(run, found, options):
    """The core.TiledVolume of a run whose Automatic Amount chose ``run.amount``: offsets bounded by its noise,
    the moved vertices kept within the deviation limit, as the whole run bounds and keeps them."""
    deviation, centre = options.get("max_deviation", 0.0), 0.5 * (found.low + found.high)
    most = int(PIECE_SHARE * run.limit) // core.TiledVolume.PIECE_BYTES
    return core.TiledVolume(run.vertices, run.amount.sigma, deviation, centre, most_pieces=most)


def restore_tiles(mesh, found, options, boxes, lookup, volume, smoothed, output, totals, run, say):
    """The volume restore's pass: the offsets solved from the tiles' sums, then each tile, read with a halo of
    two rings (the normals of its vertices' 1-rings), moved along its normals from the smoothed positions
    and written into ``output``; ``totals`` take its volumes before and after for the report."""
    tick = time.perf_counter()
    largest = volume.solve()
    margin = core.tile_margin(2, found.longest_edge)  # the corners of a tile's own triangles, and their normals
    for number, box in enumerate(boxes, 1):
        tile = read_tile(mesh, lambda p, box=box: box.reaches(p, margin), box.owns, lookup)
        edges, triangles = tile_surface(tile)
        after = smoothed.read(tile.vertices).astype(tile.positions.dtype)
        if len(triangles):  # else nothing of it lies on a surface: it stays as smoothed
            smoother = core.MeshSmoother(tile.positions, edges, faces=triangles, **options)
            smoother.still()  # welded, the border rule applied: as the smoothing found the tile
            after = volume.restored(smoother, after, tile.vertices)
            del smoother
        write_tile(tile, after, mesh, output, totals)
        totals.add_volume(*core.tile_volumes(tile.positions, after, triangles, tile.own, volume.centre))
        say(f"volume: tile {number} of {len(boxes)}, {len(tile.vertices)} vertices")
    if volume.too_many:
        run.notes.append(
            f"the scan has more than {volume.most_pieces} pieces of parts, whose sums do not fit in --memory-limit "
            f"{size_words(run.limit)} beside a tile: no closed part got its volume back (raise --memory-limit)"
        )
    elif volume.restored_parts:
        words = f"{volume.restored_parts} closed part{'s' if volume.restored_parts > 1 else ''}"
        run.notes.append(
            f"{words} got {'their' if volume.restored_parts > 1 else 'its'} volume back (largest offset "
            f"{largest:.3g}), from sums over every tile and a pass over the tiles, {time.perf_counter() - tick:.1f} s"
        )
    else:
        run.notes.append("no closed part needed its volume back (the tiles' sums found none)")
    run.volume_offset = largest


class SmoothedCopy:
    """The smoothed positions of every vertex (float64), in a scratch file beside the target: the volume
    restore's pass reads each tile's halo from it while it writes the output (each access maps the file for
    itself: only a tile's pages stay resident)."""

    def __init__(self, path, n):
        self.path, self.n = path, n
        with open(path, "wb") as file:
            file.truncate(24 * n)

    def _map(self, mode):
        return np.memmap(self.path, dtype=np.float64, mode=mode, shape=(self.n, 3))

    def write(self, rows, values):
        positions = self._map("r+")
        positions[rows] = values
        positions.flush()
        del positions

    def read(self, rows):
        positions = self._map("r")
        values = np.asarray(positions[rows])
        del positions
        return values


@contextlib.contextmanager
def smoothed_copy(temporary, n, wanted):
    """A SmoothedCopy of ``n`` vertices beside ``temporary`` (removed afterwards, however the run ends), or
    None when not ``wanted``."""
    if not wanted:
        yield None
        return
    path = files.temporary_path(temporary) + ".tmp"
    try:
        yield SmoothedCopy(path, n)
    finally:
        with contextlib.suppress(OSError):
            os.remove(path)


def plan_tiles(mesh, found, options, lookup, capacity, limit, run, restoring=False):
    """The boxes of the tiles; ``run`` takes the options every tile runs (``run.options``: the Automatic
    Amount's choice, made here, where it is asked for), the rings of halo and the margin, and whether the
    tiles add the volume restore's sums (``run.restoring``: ``restoring`` asked, and iterations to run)."""
    if core.tiles_choose(options):
        chosen = choose_on_region(mesh, found, options, lookup)
        options, run.amount = chosen.options, chosen.amount
        run.notes.append(
            f"the Automatic Amount chose {chosen.amount.iterations} iterations on a region of {chosen.region} vertices "
            f"and ran them on every tile (deviation limit {chosen.limit:.3g}); a tiled run holds or gives back no "
            "part, and Keep in Place's fold guard and its rule for open outlines judge each tile on its own "
            "(docs/large_scans.md)"
        )
    method, iterations = options.get("method", "hc"), options["iterations"]
    kept = bool(options.get("keep_in_place")) and options.get("keep_in_place") != core.AUTO
    run.options = options
    run.restoring = bool(restoring and run.amount is not None and iterations > 0)
    run.rings = core.tile_rings(method, iterations, kept, mesh.normals_per_vertex, volume=run.restoring)
    run.margin = core.tile_margin(run.rings, found.longest_edge)
    run.iterations, run.kept_in_place = iterations, kept
    scale = mesh.vertex_count / len(found.sample)
    try:
        boxes = core.tile_boxes(found.sample, scale, found.low, found.high, run.margin, 0.9 * capacity)
    except ValueError as error:
        raise ValueError(
            f"{error}: {run.rings} rings of halo ({iterations} iterations, the longest edge {found.longest_edge:.3g}) "
            f"need more room than --memory-limit {size_words(limit)} leaves; raise it, or run fewer iterations"
        ) from None
    run.tiles = len(boxes)
    return boxes


def tile_surface(tile):
    """(edges, triangles) of a tile's faces (``surface_arrays``)."""
    sizes = np.full(len(tile.corners), tile.corners.shape[1] if tile.corners.size else 3, dtype=np.int64)
    return surface_arrays(tile.corners.ravel(), sizes)


def smooth_tile(tile, options):
    """(result, the core.MeshSmoother that ran) of a tile smoothed with ``options``."""
    edges, triangles = tile_surface(tile)
    run = core.MeshSmoother(tile.positions, edges, faces=triangles if len(triangles) else None, **options)
    return run.run(), run


@dataclass
class TileJob:
    """One tile of the smoothing pass, everything a worker needs to run it (``run_tile``): the file read in blocks
    (``mesh``), where its own vertices go (``output``, and ``smoothed``, a SmoothedCopy, when closed parts get
    their volume back: then ``centre`` too), its ``box`` and ``margin`` and the ``options`` every tile runs."""

    mesh: object
    output: object
    smoothed: object
    box: object
    margin: float
    options: dict
    centre: np.ndarray | None = None


@dataclass
class TileDone:
    """A tile smoothed and written: its ``vertices`` and ``own`` counts, its ``seconds``, its ``totals`` (the
    report's sums over its own vertices) and, with the volume restore, its ``piece`` (core.TiledVolume.piece)."""

    vertices: int
    own: int
    seconds: float
    totals: object
    piece: object = None


def run_tile(job, lookup=None):
    """Read, smooth and write one tile (a ``TileJob``); returns its ``TileDone``. ``lookup``: the (n,) index the
    read numbers the tile's vertices with (-1 everywhere; made here when not given)."""
    tick = time.perf_counter()
    mesh = job.mesh
    if lookup is None:
        lookup = np.full(mesh.vertex_count, -1, dtype=index_dtype(mesh.vertex_count))
    tile = read_tile(mesh, lambda p: job.box.reaches(p, job.margin), job.box.owns, lookup)
    result, smoother = smooth_tile(tile, job.options)
    totals, piece = Totals(), None
    if job.smoothed is None:
        write_tile(tile, result, mesh, job.output, totals)
    else:  # the whole smoothed mesh is kept aside: the restore's pass reads it around each tile
        job.smoothed.write(tile.vertices[tile.own], result[tile.own])
        piece = core.TiledVolume.piece(smoother, tile.vertices, tile.own, job.centre)
    del smoother
    return TileDone(len(tile.vertices), int(tile.own.sum()), time.perf_counter() - tick, totals, piece)


def write_tile(tile, result, mesh, output, totals):
    """Write a tile's own vertices' moved positions (and the normals they touch, where the file stores one per
    vertex) into ``output``, and count their moves into ``totals``."""
    sizes = np.full(len(tile.corners), tile.corners.shape[1] if tile.corners.size else 3, dtype=np.int64)
    corners = tile.corners.ravel()
    moved = np.any(result != tile.positions, axis=1)
    own = np.flatnonzero(tile.own)
    rows = own[moved[own]]
    output.write_positions(tile.vertices[rows], result[rows])
    if mesh.normals_per_vertex and len(sizes):
        starts = np.cumsum(sizes) - sizes
        new, used = normal_maths.stored_normals(result, corners, starts, sizes, corners, len(result))
        touched = normal_maths.touched(moved, corners, starts, sizes, corners, len(result))
        rows = own[(used & touched)[own]]
        output.write_normals(tile.vertices[rows], new[rows])
    totals.add(tile.positions[own], result[own])


class Totals:
    """The sums behind a core.Change of the whole run, added tile by tile (own vertices only)."""

    def __init__(self):
        self.count = self.moved = 0
        self.sum = self.squares = self.largest = 0.0
        self.low, self.high = np.full(3, np.inf), np.full(3, -np.inf)
        self.volumes, self.open = None, False  # (before, after) times 6, where every tile adds them

    def merge(self, other):
        """Add another Totals' sums (a tile's, made where it ran)."""
        self.count += other.count
        self.moved += other.moved
        self.sum += other.sum
        self.squares += other.squares
        self.largest = max(self.largest, other.largest)
        self.low, self.high = np.minimum(self.low, other.low), np.maximum(self.high, other.high)
        if other.volumes is not None:
            self.add_volume(*other.volumes, other.open)

    def add_volume(self, before, after, open_):
        """A tile's volumes before and after (times 6) and whether it found the mesh open."""
        self.volumes = np.add(self.volumes if self.volumes is not None else 0.0, [before, after])
        self.open = self.open or open_

    def add(self, before, after):
        moves = np.asarray(after, np.float64) - np.asarray(before, np.float64)
        lengths = np.sqrt(np.einsum("ij,ij->i", moves, moves))
        self.count += len(lengths)
        self.moved += int(np.count_nonzero(lengths))
        self.sum += float(lengths.sum())
        self.squares += float(np.einsum("i,i->", lengths, lengths))
        self.largest = max(self.largest, float(lengths.max()) if lengths.size else 0.0)
        if len(after):
            self.low = np.minimum(self.low, np.asarray(after, np.float64).min(axis=0))
            self.high = np.maximum(self.high, np.asarray(after, np.float64).max(axis=0))

    def change(self, found):
        diagonal = found.diagonal
        after = float(np.linalg.norm(self.high - self.low)) if self.count else 0.0
        return core.Change(
            n_vertices=self.count,
            moved=self.moved,
            mean_displacement=self.sum / max(self.count, 1),
            max_displacement=self.largest,
            rms_displacement=float(np.sqrt(self.squares / max(self.count, 1))),
            normal_displacement=None,
            bbox_diagonal_before=diagonal,
            bbox_diagonal_after=after,
            bbox_change=(after - diagonal) / diagonal if diagonal else 0.0,
            **self._volume(),
        )

    def _volume(self):
        """The Change's volume fields: measured where every tile added its volumes and none found the mesh open."""
        if self.volumes is None or self.open:
            return {"closed": False, "volume_before": None, "volume_after": None, "volume_change": None}
        before, after = self.volumes / 6.0
        change = (after - before) / abs(before) if before else None
        return {"closed": True, "volume_before": before, "volume_after": after, "volume_change": change}


def choose_on_region(mesh, found, options, lookup):
    """core.region_amount on boxes around REGION_PLACES vertices spread evenly over the file, each box
    holding about REGION_VERTICES / REGION_PLACES vertices (by the sample)."""
    sample = found.sample
    places = sample[np.linspace(0, len(sample) - 1, REGION_PLACES).round().astype(np.int64)]
    share = REGION_VERTICES / REGION_PLACES / mesh.vertex_count * len(sample)
    boxes = [_box_around(sample, place, share, found.diagonal) for place in places]

    def reaches(points):
        inside = np.zeros(len(points), dtype=bool)
        for low, high in boxes:
            inside |= ((points >= low) & (points <= high)).all(axis=1)
        return inside

    region = read_tile(mesh, reaches, reaches, lookup)
    sizes = np.full(len(region.corners), region.corners.shape[1] if region.corners.size else 3, dtype=np.int64)
    edges, triangles = surface_arrays(region.corners.ravel(), sizes)
    return core.region_amount(region.positions, edges, triangles, options, mesh.vertex_count)


def _box_around(sample, place, count, diagonal):
    """(low, high) of the cube around ``place`` holding about ``count`` of the sample points."""
    distance = np.abs(sample - place).max(axis=1)
    if count >= len(distance):
        half = float(distance.max())
    else:
        half = float(np.partition(distance, int(count))[int(count)])
    half = max(half, 1e-9 * diagonal)
    return place - half, place + half
