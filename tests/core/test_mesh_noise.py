"""core.mesh.noise: is there noise on a mesh? ~0 on clean modelled meshes, close to the noise on noisy ones."""

import numpy as np
import pytest

import core
from bench.meshes import icosphere  # pure NumPy, no bench requirements
from bench.primitives import CAD, PRIMITIVES, TINY, joined, median_edge, mesh, moved, with_noise
from core.mesh.noise import LIGHT_FLOOR, NOISE_THRESHOLD, WHITE_SAMPLES, find_noise


def noise_of(part):
    return find_noise(part.positions, core.umbrella_operator(part.edges, len(part.positions)))


@pytest.mark.parametrize("name", [*PRIMITIVES, *CAD, *TINY])
def test_clean_meshes_have_no_noise(name):
    """Every Blender primitive at its defaults (each fill type), CAD-like parts and tiny parts: nothing
    found, and the estimate is ~0 (a fiftieth of an edge at most: the chamfered box's 45-degree steps
    give 0.011)."""
    part = {**PRIMITIVES, **CAD, **TINY}[name]()
    noise = noise_of(part)
    assert not noise.found and noise.quiet.all()
    assert noise.level() <= 0.02 * median_edge(part)


@pytest.mark.parametrize("kind", ["normal", "isotropic"])
@pytest.mark.parametrize("name", ["uv_sphere", "torus", "grid", "rounded_box", "chamfered_box", "tube"])
@pytest.mark.parametrize("ratio", [0.3, 0.5])
def test_noise_is_found_and_estimated(name, ratio, kind):
    """Noise of 0.3 and 0.5 edge lengths (scan noise of ~0.1 % of the diagonal on a 100k-vertex scan is
    about 0.3) is found, and estimated within 25 % at 0.3 (the tube, coarse with sharp rims: 50 %; the
    Grid, 121 vertices: 35 %, as the median of its 117 residuals varies by about 11 % from seed to seed, and
    reads 0.83-0.84 times the noise over 40 seeds). Heavier noise along the normals tilts the planes fitted
    to the rings: 0.5 is under-estimated by up to 30 %."""
    part, sigma = with_noise({**PRIMITIVES, **CAD}[name](), ratio, kind)
    noise = noise_of(part)
    assert noise.found and not noise.quiet.any()
    low = 0.5 if name == "tube" else 0.75 if ratio < 0.5 and name != "grid" else 0.65
    assert low * sigma < noise.level() < 1.25 * sigma


def test_curves():
    """A clean circle (edges only) has no noise; a noisy helix has, estimated within 25 %."""
    assert not noise_of(PRIMITIVES["circle"]()).found
    t = np.linspace(0, 4 * np.pi, 400)
    helix = np.stack([np.cos(t), np.sin(t), t / 10], 1)
    edges = np.stack([np.arange(399), np.arange(1, 400)], 1)
    sigma = 0.3 * np.linalg.norm(helix[1] - helix[0])
    noisy = helix + np.random.default_rng(0).normal(0, sigma, helix.shape)
    noise = find_noise(noisy, core.umbrella_operator(edges, 400))
    assert noise.found and 0.75 * sigma < noise.level() < 1.25 * sigma


def test_each_part_on_its_own():
    """A noisy sphere with a small clean cube and cone beside it, and tiny parts with noise: only the
    sphere is noisy; a part of at most four vertices never is, whatever its noise."""
    sphere, sigma = with_noise(PRIMITIVES["uv_sphere"](), 0.4, "isotropic")
    tiny = [with_noise(moved(make(), 0.1, (3, 0, 0)), 0.5, "isotropic")[0] for make in TINY.values()]
    mesh = joined(
        sphere,
        moved(PRIMITIVES["cube"](), 0.025, (1.5, 0, 0)),
        moved(PRIMITIVES["cone_ngon"](), 0.1, (0, 1.5, 0)),
        *tiny,
    )
    noise = noise_of(mesh)
    assert noise.noisy.tolist() == [True] + [False] * 5
    n = len(sphere.positions)
    assert not noise.quiet[:n].any() and noise.quiet[n:].all()
    assert noise.level() == pytest.approx(noise.sigma[0]) and 0.75 * sigma < noise.level() < 1.25 * sigma


def test_scale_position_and_orientation_do_not_matter():
    part, _ = with_noise(PRIMITIVES["torus"](), 0.3, "isotropic")
    reference = noise_of(part)
    rotation, _ = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))
    for scale in (1e-4, 1e5):
        noise = noise_of(part._replace(positions=(part.positions @ rotation.T + [3.0, -7.0, 11.0]) * scale))
        assert noise.found and noise.level() == pytest.approx(reference.level() * scale, rel=1e-6)


@pytest.mark.parametrize("kind", ["normal", "isotropic"])
def test_light_noise_is_found_by_a_half_step(kind):
    """0.05 edge lengths on the UV sphere: the estimate sees it (~0.05), below the threshold, and a half
    step towards the neighbours takes most of it away (on this quad grid a whole step would flip its
    checkerboard, not damp it): light noise found."""
    part, sigma = with_noise(PRIMITIVES["uv_sphere"](), 0.05, kind)
    noise = noise_of(part)
    assert noise.found and noise.light.all()
    assert 0.75 * sigma < noise.level() < NOISE_THRESHOLD * median_edge(part)


def test_detail_a_few_edges_wide_is_not_light_noise():
    """An icosphere with bumps of period six to seven edges: its estimate (0.056 edge lengths) is above
    LIGHT_FLOOR, but a half step keeps most of it: no noise found. With light noise added the detail
    still dominates the estimate, and the part stays quiet."""
    vertices, faces = icosphere(4)
    vertices = vertices * (1.0 + 0.08 * np.prod(np.sin(12 * vertices), axis=1))[:, None]
    part = mesh(vertices, faces.tolist())
    noise = noise_of(part)
    assert not noise.found and not noise.light.any()
    assert LIGHT_FLOOR * median_edge(part) < noise.level() < NOISE_THRESHOLD * median_edge(part)
    noisy, _ = with_noise(part, 0.03, "normal")
    assert not noise_of(noisy).found


def test_small_parts_are_judged_by_magnitude_alone():
    """A part with fewer than WHITE_SAMPLES sample vertices (the ico sphere's 42) and light noise: the
    half step is not asked, nothing found."""
    part, sigma = with_noise(PRIMITIVES["ico_sphere"](), 0.06, "normal")
    noise = noise_of(part)
    assert len(part.positions) < WHITE_SAMPLES
    assert not noise.found and LIGHT_FLOOR * median_edge(part) < noise.level() < NOISE_THRESHOLD * median_edge(part)


def flat_layouts(side=100, seed=0):
    """Flat grids of ``side`` x ``side`` vertices: quads (valence 4), regular triangles (6) and a Delaunay
    triangulation of random points (valence 3 to 10), as (name, positions, edges)."""
    from scipy.spatial import Delaunay

    x, y = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    grid = np.c_[x.ravel(), y.ravel(), np.zeros(side * side)]
    at = np.arange(side * side).reshape(side, side)
    quads = np.r_[np.c_[at[:, :-1].ravel(), at[:, 1:].ravel()], np.c_[at[:-1].ravel(), at[1:].ravel()]]
    triangles = np.r_[quads, np.c_[at[:-1, :-1].ravel(), at[1:, 1:].ravel()]]
    points = np.random.default_rng(seed).random((side * side, 2)) * side
    fans = Delaunay(points).simplices
    delaunay = np.unique(np.sort(np.r_[fans[:, [0, 1]], fans[:, [1, 2]], fans[:, [2, 0]]], axis=1), axis=0)
    return [("quads", grid, quads), ("triangles", grid, triangles), ("delaunay", np.c_[points, grid[:, 2]], delaunay)]


def test_every_layout_reads_the_same_noise():
    """Noise along the normals of flat grids: the estimate does not depend on the layout (quads read 20 %
    above regular triangles with one gain for all; each residual scaled by its layout's own gain,
    core.mesh.noise.layout_gains, they read within 5 % of each other, open borders included)."""
    sigma, reads = 0.05, {}
    for name, positions, edges in flat_layouts():
        noisy = (
            positions + np.c_[np.zeros((len(positions), 2)), np.random.default_rng(1).normal(0, sigma, len(positions))]
        )
        reads[name] = find_noise(noisy, core.umbrella_operator(edges, len(noisy))).sigma[0] / sigma
    assert max(reads.values()) < 1.05 * min(reads.values()), reads


@pytest.mark.parametrize("piece_rows", [1 << 15, 50])
@pytest.mark.parametrize("threads", [1, 3])
@pytest.mark.parametrize("halves", [0, 1])
def test_residuals_read_in_pieces_are_the_whole_readings(monkeypatch, threads, halves, piece_rows):
    """The residuals are read in pieces of consecutive sample vertices, on threads: every row's reading,
    the few rings it reads and the parts it lies in (a noisy sphere, a clean cube, a noisy grid) are the
    whole reading's, bit for bit, whatever the thread count and however many pieces; the reading yields (for
    progress and a cancel) after each round of pieces, one a thread."""
    from core import parallel
    from core.mesh import noise

    sphere, _ = with_noise(PRIMITIVES["uv_sphere"](), 0.4, "isotropic")
    grid, _ = with_noise(moved(PRIMITIVES["grid"](), 1.0, (3, 0, 0)), 0.3, "normal")
    part = joined(sphere, moved(PRIMITIVES["cube"](), 0.2, (0, 3, 0)), grid)
    operator = core.umbrella_operator(part.edges, len(part.positions))
    rows = np.flatnonzero(operator.degree > 0)
    whole = noise._residuals(part.positions, rows, operator, halves)
    monkeypatch.setattr(parallel, "thread_count", lambda: threads)
    monkeypatch.setattr(noise, "PIECE_FROM", 8)
    monkeypatch.setattr(noise, "PIECE_ROWS", piece_rows)
    rounds = noise._residual_rounds(part.positions, rows, operator, halves)
    pieces, slices = None, 0
    while pieces is None:
        try:
            next(rounds)
            slices += 1
        except StopIteration as done:
            pieces = done.value
    count = max(2 * threads, -(-rows.size // piece_rows))
    assert slices == -(-count // threads)  # a slice a round of pieces, one a thread
    for read, expected in zip(pieces, whole):
        assert np.array_equal(read, expected, equal_nan=True)
    assert np.isfinite(whole[0]).sum() > 0.9 * rows.size


def test_reading_every_vertex_takes_memory_for_a_piece_not_the_part(monkeypatch):
    """The rule that reads a part's noise on every vertex (core.mesh.collapse) on a 90,000-vertex grid: in
    pieces of 4,096 rows its peak memory is under a third of its peak in two halves of the part (the
    fewest pieces on one thread: 20 MB against 167 MB), and it reads the same estimate."""
    import tracemalloc

    from core import parallel
    from core.mesh import noise

    name, positions, edges = flat_layouts(side=300)[1]
    noisy = positions + np.c_[np.zeros((len(positions), 2)), np.random.default_rng(2).normal(0, 0.05, len(positions))]
    operator = core.umbrella_operator(edges, len(noisy))
    found = find_noise(noisy, operator)
    monkeypatch.setattr(parallel, "thread_count", lambda: 1)
    peaks, reads = [], []
    for piece_rows in (len(noisy), 4096):
        monkeypatch.setattr(noise, "PIECE_ROWS", piece_rows)
        tracemalloc.start()
        reads.append(noise.read_on_every_vertex(found, noisy, operator, np.ones(1, dtype=bool)))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert np.array_equal(reads[0], reads[1])
    assert peaks[1] < peaks[0] / 3, peaks
