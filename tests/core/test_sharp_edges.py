"""Keep Sharp Edges (core.mesh.sharp_edges and its option in core.smooth_mesh / core.MeshSmoother)."""

import math

import numpy as np
import pytest

import core
from bench.primitives import CAD, PRIMITIVES, TINY
from core.geometry import face_normals
from core.mesh import sharp_edges
from core.mesh.sharp_edges import FaceRings, SharpSmoothing, filter_normals, fit_vertices, sharp_smooth
from core.slices import to_end


def box(cells=12, size=2.0):
    """A closed cube of side ``size``, each side a grid of ``cells`` x ``cells`` squares split into
    triangles, outward, vertices shared along the edges: 12 sharp edges of 90 degrees."""
    points, triangles, offset = [], [], 0
    ticks = np.arange(cells + 1)
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        iu, iv = (a.ravel() for a in np.meshgrid(ticks, ticks, indexing="ij"))
        a = (iu * (cells + 1) + iv).reshape(cells + 1, cells + 1)[:-1, :-1].ravel()
        b, c, d = a + cells + 1, a + cells + 2, a + 1
        quads = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        for side in (0, cells):
            lattice = np.zeros((iu.size, 3), np.int64)
            lattice[:, u], lattice[:, v], lattice[:, axis] = iu, iv, side
            points.append(lattice)
            triangles.append((quads if side else quads[:, ::-1]) + offset)
            offset += iu.size
    lattice = np.concatenate(points)
    unique, inverse = np.unique(lattice, axis=0, return_inverse=True)
    faces = inverse.reshape(-1)[np.concatenate(triangles)]
    return unique * (size / cells) - size / 2.0, faces


def edges_of(faces):
    return faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)


def vertex_normals(points, faces):
    a, b, c = (points[faces[:, k]] for k in range(3))
    summed = np.zeros_like(points)
    for k in range(3):
        np.add.at(summed, faces[:, k], np.cross(b - a, c - a))
    return summed / np.linalg.norm(summed, axis=1, keepdims=True)


def volume(points, faces):
    a, b, c = (points[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def crease_pairs(points, faces, degrees=30.0):
    """(face a, face b, dihedral angle in degrees) of every edge whose faces meet at more than ``degrees``."""
    seen, pairs = {}, []
    for f, face in enumerate(faces):
        for k in range(3):
            key = tuple(sorted((int(face[k]), int(face[(k + 1) % 3]))))
            if key in seen:
                pairs.append((seen[key], f))
            else:
                seen[key] = f
    a, b = np.array(pairs).T
    angles = dihedral(points, faces, a, b)
    sharp = angles > degrees
    return a[sharp], b[sharp], angles[sharp]


def dihedral(points, faces, a, b):
    n = face_normals(points, faces)
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n[a], n[b]), -1.0, 1.0)))


def noisy_box(share=0.005, kind="normal", seed=3, cells=16):
    clean, faces = box(cells)
    sigma = share * np.linalg.norm(clean.max(0) - clean.min(0))
    rng = np.random.default_rng(seed)
    if kind == "normal":
        noisy = clean + vertex_normals(clean, faces) * rng.normal(0.0, sigma, (len(clean), 1))
    else:
        noisy = clean + rng.normal(0.0, sigma, clean.shape)
    return clean, noisy, faces


@pytest.mark.parametrize("kind", ["normal", "iso"])
def test_box_keeps_its_sharp_edges_and_volume(kind):
    clean, noisy, faces = noisy_box(0.005, kind)
    a, b, angles = crease_pairs(clean, faces)
    assert a.size == 12 * 16  # every mesh edge along the 12 creases
    smoothed = core.smooth_mesh(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=3)
    noisy_error = np.abs(dihedral(noisy, faces, a, b) - angles).mean()
    error = np.abs(dihedral(smoothed, faces, a, b) - angles).mean()
    assert error < 5.0 < noisy_error
    assert abs(volume(smoothed, faces) / volume(clean, faces) - 1.0) <= 0.005
    assert off_the_cube(smoothed) < 0.5 * off_the_cube(noisy)
    turned = np.einsum("ij,ij->i", face_normals(smoothed, faces), face_normals(clean, faces)) < 0.0
    assert not turned.any()


def off_the_cube(points, half=1.0):
    """RMS distance of points near the surface of the cube [-half, half]^3 to it."""
    return float(np.sqrt(np.mean((np.abs(points).max(axis=1) - half) ** 2)))


def test_hc_rounds_the_edges_that_keep_sharp_edges_keeps():
    clean, noisy, faces = noisy_box(0.005, "normal")
    a, b, angles = crease_pairs(clean, faces)
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    hc = core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=10)
    sharp = sharp_smooth(noisy, faces, iterations=3)
    assert (
        np.abs(dihedral(sharp, faces, a, b) - angles).mean() < 0.5 * np.abs(dihedral(hc, faces, a, b) - angles).mean()
    )


def test_flat_plane_with_noise_along_its_normal_gets_flat():
    side = 21
    u, v = np.meshgrid(np.linspace(0, 1, side), np.linspace(0, 1, side))
    grid = np.arange(side * side).reshape(side, side)
    a, b, c, d = grid[:-1, :-1].ravel(), grid[:-1, 1:].ravel(), grid[1:, 1:].ravel(), grid[1:, :-1].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    noisy = np.c_[u.ravel(), v.ravel(), np.random.default_rng(5).normal(0.0, 0.005, side * side)]
    interior = (u.ravel() > 0) & (u.ravel() < 1) & (v.ravel() > 0) & (v.ravel() < 1)
    smoothed = sharp_smooth(noisy, faces, iterations=5)
    assert smoothed[interior, 2].std() < 0.25 * noisy[interior, 2].std()  # a fifth of the noise: its smooth bumps
    assert np.abs(smoothed[interior, :2] - noisy[interior, :2]).max() < 0.005  # along the normal, not the plane


def test_fixed_and_zero_influence_vertices_stay_bit_for_bit():
    _, noisy, faces = noisy_box(0.005, "iso", cells=8)
    noisy = noisy.astype(np.float32)
    fixed = np.zeros(len(noisy), bool)
    fixed[::7] = True
    influence = np.ones(len(noisy))
    influence[3::11] = 0.0
    smoothed = sharp_smooth(noisy, faces, iterations=2, fixed=fixed, influence=influence)
    still = fixed | (influence == 0.0)
    assert smoothed.dtype == np.float32
    assert np.array_equal(smoothed[still], noisy[still])
    assert np.all(np.any(smoothed[~still] != noisy[~still], axis=1))
    run = core.smooth_mesh(
        noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=2, fixed=np.flatnonzero(fixed)
    )
    assert np.array_equal(run[fixed], noisy[fixed])


def test_half_influence_moves_less():
    _, noisy, faces = noisy_box(0.005, "iso", cells=8)
    full = sharp_smooth(noisy, faces, iterations=1)
    half = sharp_smooth(noisy, faces, iterations=1, influence=np.full(len(noisy), 0.5))
    assert 0.3 < np.linalg.norm(half - noisy) / np.linalg.norm(full - noisy) < 0.8


def _loop_filter(normals, faces, threshold, iterations):
    """Sun et al.'s normal filtering written from the paper, face by face, with core.mesh.sharp_edges' rule for
    a face that no other face of its ring is within the angle of: the plain mean of its ring (if that is
    at least a tenth of a unit long)."""
    around = {}
    for f, face in enumerate(faces):
        for v in face:
            around.setdefault(int(v), set()).add(f)
    lonely_seen = 0
    for _ in range(iterations):
        new = np.empty_like(normals)
        for i, face in enumerate(faces):
            ring = set().union(*(around[int(v)] for v in face))
            total, similar = np.zeros(3), 0
            for j in ring:
                cosine = float(normals[i] @ normals[j])
                if cosine > threshold:
                    total += (cosine - threshold) ** 2 * normals[j]
                    similar += j != i
            mean = sum(normals[j] for j in ring) / len(ring)
            if not similar and mean @ mean >= 0.01:
                total = mean
                lonely_seen += 1
            new[i] = total / np.linalg.norm(total) if np.linalg.norm(total) > 0 else normals[i]
        normals = new
    return normals, lonely_seen


def _loop_fit(points, faces, normals, iterations):
    """Sun et al.'s vertex update written from the paper, vertex by vertex."""
    points = points.copy()
    for _ in range(iterations):
        new = points.copy()
        for i in range(len(points)):
            around = [f for f, face in enumerate(faces) if i in face]
            move = np.zeros(3)
            for f in around:
                centroid = points[faces[f]].mean(axis=0)
                move += normals[f] * (normals[f] @ (centroid - points[i]))
            new[i] = points[i] + move / len(around)
        points = new
    return points


@pytest.mark.parametrize("share", [0.02, 0.1])
def test_vectorised_filter_and_fit_equal_the_papers_loops(share, monkeypatch):
    """In double precision the filter is the loop's to rounding; in its own single precision to 1e-5."""
    _, noisy, faces = noisy_box(share, "iso", cells=3)
    rings = FaceRings(faces, len(noisy))
    normals = face_normals(noisy, faces)
    threshold = math.cos(math.radians(40.0))
    expected, lonely = _loop_filter(normals, faces, threshold, 4)
    assert np.allclose(filter_normals(normals, rings, threshold, iterations=4), expected, rtol=0.0, atol=1e-5)
    monkeypatch.setattr(sharp_edges, "FILTER_DTYPE", np.float64)
    filtered = filter_normals(normals, rings, threshold, iterations=4)
    assert np.allclose(filtered, expected, atol=1e-12)
    assert (lonely > 0) == (share > 0.05)  # heavy noise leaves faces without a similar neighbour
    assert not np.allclose(filtered, normals, atol=1e-3)  # it did filter
    fitted = fit_vertices(noisy, filtered, rings, np.ones(len(noisy)), iterations=3)
    assert np.allclose(fitted, _loop_fit(noisy, faces, filtered, 3), atol=1e-12)


@pytest.mark.parametrize("degrees", [40.0, 100.0])
def test_faces_without_a_normal_filter_as_in_the_papers_loop(degrees, monkeypatch):
    """A zero normal (a degenerate triangle) is not within an angle below 90 degrees of itself: such a face
    is counted apart from the others' weights, and takes its ring's mean as the loop does."""
    _, noisy, faces = noisy_box(0.02, "iso", cells=3)
    rings = FaceRings(faces, len(noisy))
    normals = face_normals(noisy, faces)
    normals[[3, 17]] = 0.0
    threshold = math.cos(math.radians(degrees))
    monkeypatch.setattr(sharp_edges, "FILTER_DTYPE", np.float64)
    filtered = filter_normals(normals, rings, threshold, iterations=3)
    expected, _ = _loop_filter(normals, faces, threshold, 3)
    assert np.allclose(filtered, expected, atol=1e-12)
    assert np.all(np.linalg.norm(filtered[[3, 17]], axis=1) > 0.99)  # they took their rings' normals


def test_public_products_give_what_scipys_kernels_give(monkeypatch):
    """Without SciPy's private kernel (another SciPy), the public products run the same passes."""
    _, noisy, faces = noisy_box(0.02, "iso", cells=4)
    with_kernels = sharp_smooth(noisy, faces, iterations=2)
    monkeypatch.setattr(sharp_edges, "_csr_matvec", None)
    monkeypatch.setattr(core.parallel, "_csr_matvec", None)
    public = sharp_smooth(noisy, faces, iterations=2)
    assert np.allclose(public, with_kernels, rtol=0.0, atol=1e-12)
    assert not np.allclose(public, noisy, atol=1e-4)  # it did smooth


def test_off_is_bit_identical():
    _, noisy, faces = noisy_box(0.005, "iso", cells=8)
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    for options in ({}, {"alpha": 0.1, "beta": 0.6, "iterations": 10}, {"weld": True}):
        plain = core.smooth_mesh(noisy, edges, faces=faces, **options)
        off = core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=False, sharpness_angle=0.3, **options)
        assert np.array_equal(plain, off)
    on = core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=True)
    assert not np.array_equal(on, core.smooth_mesh(noisy, edges, faces=faces))


def test_bad_input_raises_clear_errors():
    clean, faces = box(4)
    edges = faces[:, :2]
    with pytest.raises(ValueError, match="needs the faces"):
        core.smooth_mesh(clean, edges, keep_sharp_edges=True)
    with pytest.raises(ValueError, match="has none"):
        core.smooth_mesh(clean, edges, faces=np.zeros((0, 3), int), keep_sharp_edges=True)
    with pytest.raises(ValueError, match="has none"):
        sharp_smooth(clean, np.zeros((0, 3), int))
    for angle in (0.0, -0.1, math.pi, 4.0, float("nan"), "45"):
        with pytest.raises(ValueError, match="sharpness_angle"):
            core.smooth_mesh(clean, edges, faces=faces, keep_sharp_edges=True, sharpness_angle=angle)
    with pytest.raises(ValueError, match="keep_sharp_edges"):
        core.smooth_mesh(clean, edges, faces=faces, keep_sharp_edges="yes")
    with pytest.raises(ValueError, match="between 0 and"):
        sharp_smooth(clean, faces + len(clean))


def test_slices_progress_and_cancel():
    _, noisy, faces = noisy_box(0.005, "iso", cells=8)
    before = noisy.copy()
    run = core.MeshSmoother(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=4)
    fractions = list(run.steps(chunk=1))
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and len(fractions) >= 4
    assert run.report.keep_sharp_edges and run.report.iterations == 4
    assert np.array_equal(run.result, sharp_smooth(noisy, faces, iterations=4, guided=True))
    with pytest.raises(core.Cancelled):
        core.smooth_mesh(
            noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=4, progress=lambda f: f < 0.3
        )
    abandoned = core.MeshSmoother(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True).steps(chunk=1)
    next(abandoned)
    abandoned.close()
    assert np.array_equal(noisy, before)


def test_welding_runs_a_soup_like_its_welded_mesh():
    _, noisy, faces = noisy_box(0.005, "iso", cells=6)
    soup = noisy[faces.ravel()]
    soup_faces = np.arange(soup.shape[0]).reshape(-1, 3)
    soup_edges = soup_faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    welded = core.smooth_mesh(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=2)
    from_soup = core.smooth_mesh(soup, soup_edges, faces=soup_faces, keep_sharp_edges=True, iterations=2, weld=True)
    assert np.allclose(from_soup, welded[faces.ravel()], atol=1e-12)


def test_automatic_amount_leaves_a_clean_part_and_smooths_a_noisy_one():
    clean, faces = box(12)
    diagonal = np.linalg.norm(clean.max(0) - clean.min(0))
    still, report = core.smooth_mesh(clean, edges_of(faces), faces=faces, keep_sharp_edges=True, return_report=True)
    assert np.linalg.norm(still - clean, axis=1).max() <= 0.001 * diagonal
    assert report.keep_sharp_edges and report.amount is not None
    _, noisy, faces = noisy_box(0.005, "normal", cells=16)
    clean16, _ = box(16)
    smoothed, report = core.smooth_mesh(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, return_report=True)
    assert report.amount.noise_found and report.iterations > 0
    assert off_the_cube(smoothed) < 0.5 * off_the_cube(noisy)
    assert abs(volume(smoothed, faces) / volume(clean16, faces) - 1.0) <= 0.005


def test_default_angle_is_in_range():
    assert math.radians(20) <= sharp_edges.DEFAULT_SHARPNESS_ANGLE <= math.radians(60)
    assert (
        core.MeshSmoother(box(2)[0], edges_of(box(2)[1]), faces=box(2)[1], keep_sharp_edges=True).sharpness_angle
        == sharp_edges.DEFAULT_SHARPNESS_ANGLE
    )


CLEAN_WITH_FACES = {name: make for name, make in {**PRIMITIVES, **CAD, **TINY}.items() if make().faces}


@pytest.mark.parametrize("name", CLEAN_WITH_FACES)
def test_noise_free_meshes_stay_with_the_automatic_amount(name):
    """Blender's primitives, CAD-like parts and tiny parts, noise-free: Keep Sharp Edges at the Automatic
    Amount moves them by at most 0.1 % of the diagonal, as HC's default contract says."""
    part = CLEAN_WITH_FACES[name]()
    result = core.smooth_mesh(part.positions, part.edges, faces=part.faces, keep_sharp_edges=True, weld=True)
    diagonal = np.linalg.norm(np.ptp(part.positions, axis=0))
    assert np.linalg.norm(result - part.positions, axis=1).max() <= 1e-3 * diagonal


def test_big_meshes_yield_between_filtering_passes(monkeypatch):
    """From PASS_SLICES_FROM triangles a step is sliced at every filtering pass, every FIT_SLICE fitting
    passes and between unfolding rounds (a cancel waits for one slice, not a step); the result is the same."""
    _, noisy, faces = noisy_box(0.005, "iso", cells=6)
    whole = SharpSmoothing(noisy, faces, iterations=2)
    coarse = list(whole.steps(chunk=1))
    monkeypatch.setattr(sharp_edges, "PASS_SLICES_FROM", 10)
    sliced = SharpSmoothing(noisy, faces, iterations=2)
    fine = list(sliced.steps(chunk=1))
    assert coarse == [0.5, 1.0]
    fewest = sharp_edges.NORMAL_ITERATIONS + sharp_edges.FIT_SLICES + 1
    assert 2 * fewest <= len(fine) <= 2 * sharp_edges.STEP_SLICES and fine == sorted(fine) and fine[-1] == 1.0
    assert np.array_equal(sliced.result(), whole.result())


def test_big_meshes_yield_while_the_rings_and_the_guidance_are_made(monkeypatch):
    """On big meshes the face rings are built in slices (steps() yields 0.0 after each stage) and a guided
    step yields within the guidance (GUIDED_SLICES), after it and after each choice of the nearest planes
    too: a cancel never waits for the whole set-up. Sliced or not, the rings and the result are the same."""
    _, noisy, faces = noisy_box(0.005, "iso", cells=6)
    whole = SharpSmoothing(noisy, faces, iterations=2, guided=True)
    at_once = list(whole.steps())
    monkeypatch.setattr(sharp_edges, "PASS_SLICES_FROM", 10)
    sliced = SharpSmoothing(noisy, faces, iterations=2, guided=True)
    fine = list(sliced.steps(chunk=1))
    stages = fine.index(next(f for f in fine if f > 0.0))
    assert at_once == [1.0] and stages == 3
    per_step = sharp_edges.GUIDED_SLICES + sharp_edges.NORMAL_ITERATIONS + sharp_edges.FIT_SLICES + 1
    assert stages + 2 * per_step <= len(fine) <= stages + 2 * (sharp_edges.STEP_SLICES + 1)
    assert fine == sorted(fine) and fine[-1] == 1.0
    assert np.array_equal(sliced.result(), whole.result())
    rings = to_end(FaceRings.in_slices(faces, len(noisy)))
    reference = FaceRings(faces, len(noisy))
    for name in ("indptr", "indices", "counts", "corners", "across", "border", "faces_at"):
        assert np.array_equal(getattr(rings, name), getattr(reference, name)), name
    assert (rings.ring != reference.ring).nnz == 0 and (rings.incidence != reference.incidence).nnz == 0


def _loop_guidance(normals, faces):
    """``guidance_normals`` written from its definition, face by face and patch by patch."""
    around, edges = {}, {}
    for f, face in enumerate(faces):
        for k in range(3):
            around.setdefault(int(face[k]), set()).add(f)
            edges.setdefault(tuple(sorted((int(face[k]), int(face[(k + 1) % 3])))), []).append(f)
    rings = [sorted(set().union(*(around[int(v)] for v in face))) for face in faces]
    steep, summed = np.zeros(len(faces)), np.zeros(len(faces))
    for shared in edges.values():
        for f in shared:
            other = next((g for g in shared if g != f), f)
            step = np.linalg.norm(normals[f] - normals[other])
            steep[f], summed[f] = max(steep[f], step), summed[f] + step

    def patch(faces_of):  # (unit mean, consistency H)
        mean = sum(normals[a] for a in faces_of)
        mean = mean / np.linalg.norm(mean)
        spread = max(1.0 - normals[a] @ mean for a in faces_of)
        return mean, spread * max(steep[a] for a in faces_of) / (1e-9 + sum(summed[a] for a in faces_of))

    face_rings = [patch(ring) for ring in rings]
    vertex_rings = {v: patch(sorted(fs)) for v, fs in around.items()}
    out = []
    for ring, face in zip(rings, faces):
        j = min(ring, key=lambda j: (face_rings[j][1], j))
        corner = min(range(3), key=lambda k: (vertex_rings[int(face[k])][1], k))
        vertex = vertex_rings[int(face[corner])]
        out.append(vertex[0] if sharp_edges.VERTEX_RING_WEIGHT * vertex[1] < face_rings[j][1] else face_rings[j][0])
    return np.array(out)


def test_guidance_equals_its_definition_as_a_loop():
    _, noisy, faces = noisy_box(0.02, "iso", cells=3)
    normals = face_normals(noisy, faces)
    guidance = sharp_edges.guidance_normals(normals, FaceRings(faces, len(noisy)))
    expected = _loop_guidance(normals, faces)
    assert np.allclose(guidance, expected, atol=1e-12)
    assert not np.allclose(guidance, normals, atol=1e-3)
    vertex_means = np.array([normals[(faces == v).any(axis=1)].sum(0) for v in range(len(noisy))])
    vertex_means /= np.linalg.norm(vertex_means, axis=1, keepdims=True)
    from_vertices = (np.abs(guidance[:, None, :] - vertex_means[None]).max(axis=2) < 1e-12).any(axis=1)
    assert 0 < from_vertices.sum() < len(faces)  # both kinds of patch were chosen


def slab(cells=12, layers=2):
    """A closed box 2 x 2 x (layers / cells * 2): a thin plate whose rim is ``layers`` cells tall."""
    points, faces = box(cells)
    points = points.copy()
    points[:, 2] = np.clip(points[:, 2], -layers / cells, layers / cells)  # the rows above squashed onto the top
    unique, inverse = np.unique(np.round(points, 12), axis=0, return_inverse=True)
    faces = inverse.reshape(-1)[faces]
    return unique, faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])]


def test_guidance_of_a_thin_plates_rim_comes_from_vertex_rings():
    """On a clean plate whose rim is two faces tall every face ring of a rim face reaches over a crease;
    the rings of the rim's middle vertices do not: every rim face off the corners gets its own normal."""
    points, faces = slab()
    normals = face_normals(points, faces)
    guidance = sharp_edges.guidance_normals(normals, FaceRings(faces, len(points)))
    centre = points[faces].mean(axis=1)
    rim = np.abs(normals[:, 2]) < 0.5
    off_corners = (np.abs(centre[:, :2]) < 1.0 - 2.0 / 12).any(axis=1)
    assert (rim & off_corners).sum() > 100
    assert np.allclose(guidance[rim & off_corners], normals[rim & off_corners], atol=1e-12)


@pytest.mark.parametrize("share, degrees", [(0.02, 40.0), (0.2, 10.0)])
def test_guided_filter_with_fixed_weights_equals_the_loop_on_the_guidance(share, degrees, monkeypatch):
    """With guidance, the weights are the guidance's cosines, the same for every pass: one guided pass is the
    paper's pass with the cosines of the guidance (in double precision, to rounding); a face no other face's
    guidance is within the angle of takes its ring's mean, as in the plain filter (heavy noise, a narrow
    angle: many such faces)."""
    monkeypatch.setattr(sharp_edges, "FILTER_DTYPE", np.float64)
    _, noisy, faces = noisy_box(share, "iso", cells=3)
    rings = FaceRings(faces, len(noisy))
    normals = face_normals(noisy, faces)
    guidance = sharp_edges.guidance_normals(normals, rings)
    threshold = math.cos(math.radians(degrees))
    once = filter_normals(normals, rings, threshold, iterations=1, guidance=guidance)
    around = {}
    for f, face in enumerate(faces):
        for v in face:
            around.setdefault(int(v), set()).add(f)
    lonely = 0
    for i, face in enumerate(faces):
        ring = set().union(*(around[int(v)] for v in face))
        weights = {j: max(float(guidance[i] @ guidance[j]) - threshold, 0.0) ** 2 for j in ring}
        total = sum(w * normals[j] for j, w in weights.items())
        if sum(w for j, w in weights.items() if j != i) == 0.0:  # lonely
            lonely += 1
            mean = sum(normals[j] for j in ring) / len(ring)
            total = mean if mean @ mean >= 0.01 else normals[i]
        assert np.allclose(once[i], total / np.linalg.norm(total), atol=1e-12)
    assert (lonely > 0) == (share > 0.1)


def wedge(cells=24, degrees=45.0):
    """Two planes meeting at a crease of ``degrees`` along the grid line u = 0: (2 cells + 1) x (cells + 1)
    points, triangles."""
    u, v = np.meshgrid(np.linspace(-1, 1, 2 * cells + 1), np.linspace(0, 1, cells + 1), indexing="ij")
    z = np.where(u > 0, u * math.tan(math.radians(degrees)), 0.0)
    points = np.c_[u.ravel(), v.ravel(), z.ravel()]
    grid = np.arange(points.shape[0]).reshape(u.shape)
    a, b, c, d = grid[:-1, :-1].ravel(), grid[1:, :-1].ravel(), grid[1:, 1:].ravel(), grid[:-1, 1:].ravel()
    return points, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


@pytest.mark.parametrize("seed", [0, 1])
def test_guided_filter_finds_a_noisy_wedges_planes_where_the_plain_filter_cannot(seed):
    """Noise of 0.35 edge lengths tilts single faces by ~37 degrees, nearly the wedge's 45: the plain filter
    at 30 degrees leaves ~18 degrees of error on the faces off the crease and the borders, the guided one
    (weights from the steadier patch means) under 5."""
    points, faces = wedge()
    edge = 1.0 / 24
    noisy = points + np.random.default_rng(seed).normal(0.0, 0.35 * edge, points.shape)
    rings = FaceRings(faces, len(points))
    normals = face_normals(noisy, faces)
    threshold = math.cos(math.radians(30.0))
    guided = filter_normals(normals, rings, threshold, guidance=sharp_edges.guidance_normals(normals, rings))
    plain = filter_normals(normals, rings, threshold)
    centre = points[faces].mean(axis=1)
    inner = (np.abs(centre[:, 0]) > 2 * edge) & (np.abs(centre[:, 0]) < 1 - 2 * edge)
    inner &= (centre[:, 1] > 2 * edge) & (centre[:, 1] < 1 - 2 * edge)
    clean = face_normals(points, faces)

    def error(n):
        return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n, clean), -1.0, 1.0)))[inner].mean()

    assert error(guided) < 5.0 < 15.0 < error(plain)


def test_guidance_of_a_clean_box_is_its_normals_but_at_corners_and_the_box_stays():
    """On a clean box every face off the corners lies in a patch on one side (spread 0): its guidance is its
    normal. Every patch around a face at a corner is mixed, and its guidance a blend of the sides; there
    the nearest plane, the face's own, gives its normal back: the box stays put."""
    clean, faces = box(8)
    normals = face_normals(clean, faces)
    rings = FaceRings(faces, len(clean))
    guidance = sharp_edges.guidance_normals(normals, rings)
    off = np.einsum("ij,ij->i", normals, guidance) < 1.0 - 1e-12
    at_corner = (np.abs(clean[faces]) == 1.0).all(axis=2).any(axis=1)  # a corner of the face is the box's
    assert off.any() and not (off & ~at_corner).any()
    assert np.array_equal(sharp_edges.nearest_plane_normals(clean, guidance, rings), normals)
    assert np.allclose(sharp_smooth(clean, faces, iterations=3, guided=True), clean, atol=1e-12)
    points, triangles = wedge(8)
    assert np.allclose(sharp_smooth(points, triangles, iterations=3, guided=True), points, atol=1e-12)


def _loop_nearest_planes(points, normals, faces):
    """``nearest_plane_normals`` written from its definition, face by face."""
    around = {}
    for f, face in enumerate(faces):
        for v in face:
            around.setdefault(int(v), set()).add(f)
    out = np.empty_like(normals)
    for i, face in enumerate(faces):
        ring = sorted(set().union(*(around[int(v)] for v in face)))
        costs = [sum(float(normals[j] @ (x - points[faces[j]].mean(axis=0))) ** 2 for x in points[face]) for j in ring]
        out[i] = normals[ring[int(np.argmin(costs))]]  # the first on a tie
    return out


def test_nearest_planes_equal_their_definition_as_a_loop():
    _, noisy, faces = noisy_box(0.02, "iso", cells=3)
    rings = FaceRings(faces, len(noisy))
    filtered = filter_normals(face_normals(noisy, faces), rings, math.cos(math.radians(40.0)), iterations=3)
    chosen = sharp_edges.nearest_plane_normals(noisy, filtered, rings)
    assert np.array_equal(chosen, _loop_nearest_planes(noisy, filtered, faces))
    assert not np.array_equal(chosen, filtered)


def test_a_crease_row_between_the_sides_takes_the_side_it_lies_on():
    """A clean wedge whose faces along the crease were given the halfway normal: each takes its side's."""
    points, faces = wedge(8)
    clean = face_normals(points, faces)
    centre = points[faces].mean(axis=1)
    row = np.abs(centre[:, 0]) < 1.0 / 8
    blended = clean.copy()
    blended[row] = [-math.sin(math.radians(22.5)), 0.0, math.cos(math.radians(22.5))]  # halfway
    chosen = sharp_edges.nearest_plane_normals(points, blended, FaceRings(faces, len(points)))
    assert np.allclose(chosen, clean, atol=1e-12)


def test_sun_et_als_filter_without_guidance(monkeypatch):
    """guided=False (SharpSmoothing's default): a step is Sun et al.'s filter (the faces' own normals) and
    the fitting; guided=True is another step."""
    _, noisy, faces = noisy_box(0.01, "iso", cells=6)
    rings = FaceRings(faces, len(noisy))
    threshold = math.cos(sharp_edges.DEFAULT_SHARPNESS_ANGLE)
    filtered = filter_normals(face_normals(noisy, faces), rings, threshold)
    fitted = fit_vertices(noisy, filtered, rings, np.ones(len(noisy)))
    monkeypatch.setattr(sharp_edges, "TANGENTIAL", 0.0)
    plain = sharp_smooth(noisy, faces, iterations=1, push_back=False)
    assert np.allclose(plain, fitted, atol=1e-12)
    assert not np.allclose(sharp_smooth(noisy, faces, iterations=1, push_back=False, guided=True), fitted, atol=1e-6)


def test_the_filter_is_guided_where_noise_is_found(monkeypatch):
    """The guidance runs on a noisy part, with the Automatic Amount and with a set number of steps alike
    (the result then is SharpSmoothing's guided run of those steps); not on a clean part, steps set or not."""
    calls = []
    guidance = sharp_edges.guidance_steps
    monkeypatch.setattr(sharp_edges, "guidance_steps", lambda *a: calls.append(1) or guidance(*a))
    _, noisy, faces = noisy_box(0.005, "iso", cells=8)
    core.smooth_mesh(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True)
    assert calls
    calls.clear()
    set_steps = core.smooth_mesh(noisy, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=2)
    assert len(calls) == 2
    guided = SharpSmoothing(noisy, faces, iterations=2, guided=True)
    assert np.array_equal(set_steps, to_end_result(guided))
    calls.clear()
    clean, faces = box(8)
    core.smooth_mesh(clean, edges_of(faces), faces=faces, keep_sharp_edges=True)
    core.smooth_mesh(clean, edges_of(faces), faces=faces, keep_sharp_edges=True, iterations=2)
    assert not calls


def to_end_result(run):
    """A SharpSmoothing's result after all its steps."""
    for _ in run.steps():
        pass
    return run.result()


def test_a_coarse_cube_is_why_the_guidance_needs_noise():
    """Every face of a cube of 12 triangles is at a corner: the guidance blends the sides, Sun et al.'s
    filter keeps them."""
    positions = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    quads = [[0, 1, 3, 2], [2, 3, 7, 6], [6, 7, 5, 4], [4, 5, 1, 0], [2, 6, 4, 0], [7, 3, 1, 5]]
    assert np.allclose(sharp_smooth(positions, quads, iterations=2), positions, atol=1e-12)
    assert not np.allclose(sharp_smooth(positions, quads, iterations=2, guided=True), positions, atol=0.1)


def _grid(cells=4):
    """A flat square grid of ``cells`` x ``cells`` squares split into triangles, facing +z."""
    ticks = np.arange(cells + 1, dtype=float)
    u, v = (a.ravel() for a in np.meshgrid(ticks, ticks, indexing="ij"))
    a = (np.arange((cells + 1) ** 2).reshape(cells + 1, cells + 1))[:-1, :-1].ravel()
    b, c, d = a + cells + 1, a + cells + 2, a + 1
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    points = np.c_[u, v, np.zeros(u.size)]
    if face_normals(points, faces)[0, 2] < 0:
        faces = faces[:, ::-1]
    return points, faces


def _loop_unfold(points, start, before, faces, normals, around, rounds=sharp_edges.FOLD_ROUNDS):
    """The unfolding from its definition, triangle by triangle."""
    points = points.copy()
    folded = [before[f] @ normals[f] < 0.0 or before[f] @ around[f] < 0.0 for f in range(len(faces))]
    for _ in range(rounds):
        now = face_normals(points, faces)
        turned = [not folded[f] and (now[f] @ normals[f] < 0.0 or now[f] @ around[f] < 0.0) for f in range(len(faces))]
        if not any(turned):
            break
        corners = {int(v) for f in range(len(faces)) if turned[f] for v in faces[f]}
        for v in corners:
            points[v] = start[v] + 0.5 * (points[v] - start[v])
    return points


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_unfolding_equals_its_definition_as_a_loop(seed):
    flat, faces = _grid(6)
    rng = np.random.default_rng(seed)
    start = flat + rng.normal(0.0, 0.4, flat.shape) * [1, 1, 0]  # noise along the plane folds triangles
    points = flat + rng.normal(0.0, 0.4, flat.shape) * [1, 1, 0]
    before = face_normals(start, faces)
    normals = around = np.tile([0.0, 0.0, 1.0], (len(faces), 1))
    expected = _loop_unfold(points, start, before, faces, normals, around)
    unfolded = points.copy()
    for _ in sharp_edges._unfold(unfolded, start, before, faces, normals, around):
        pass
    assert np.array_equal(unfolded, expected)
    assert (face_normals(start, faces)[:, 2] < 0).any() and (face_normals(points, faces)[:, 2] < 0).any()
    assert not np.array_equal(unfolded, points)


def test_a_step_unfolds_what_noise_folded_and_halves_what_it_folds():
    flat, faces = _grid(4)
    folded = flat.copy()
    folded[6, :2] += [1.6, 1.6]  # an inner vertex pushed across its ring along the plane: triangles turn over
    assert (face_normals(folded, faces)[:, 2] < 0).any()
    normals = around = np.tile([0.0, 0.0, 1.0], (len(faces), 1))
    unfolded = flat.copy()  # the step moves it back: its move is kept
    for _ in sharp_edges._unfold(unfolded, folded, face_normals(folded, faces), faces, normals, around):
        pass
    assert np.array_equal(unfolded, flat)
    turned = folded.copy()  # the step folds it: its corners' moves are halved until no triangle is turned
    for _ in sharp_edges._unfold(turned, flat, face_normals(flat, faces), faces, normals, around):
        pass
    assert (face_normals(turned, faces)[:, 2] > 0).all()
    assert not np.array_equal(turned, folded)
