"""core.choose_amount: the Automatic Amount for meshes (core/mesh/amount.py)."""

import math
import threading
import warnings

import numpy as np
import pytest

import core
from bench.meshes import icosphere  # pure NumPy, no bench requirements
from core import parallel
from core.mesh import amount as noise


def edges_of(faces):
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return np.unique(pairs, axis=0)


def bumpy_sphere(level=4):
    """A unit sphere with bumps a few edges wide: detail that too much smoothing removes."""
    vertices, faces = icosphere(level)
    radius = 1.0 + 0.08 * np.sin(6 * vertices[:, 0]) * np.sin(6 * vertices[:, 1]) * np.sin(6 * vertices[:, 2])
    return vertices * radius[:, None], faces


def edge_length(vertices, edges):
    return float(np.median(np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)))


def with_normal_noise(vertices, ratio, edges, seed=0):
    """Gaussian noise along the radial direction, ``ratio`` times the median edge length."""
    normals = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    sigma = ratio * edge_length(vertices, edges)
    return vertices + normals * np.random.default_rng(seed).normal(0.0, sigma, (len(vertices), 1)), sigma


def surface_error(points, vertices):
    """RMS distance of ``points`` to the bumpy sphere through ``vertices``, approximated radially."""
    direction = points / np.linalg.norm(points, axis=1, keepdims=True)
    true_radius = 1.0 + 0.08 * np.sin(6 * direction[:, 0]) * np.sin(6 * direction[:, 1]) * np.sin(6 * direction[:, 2])
    return float(np.sqrt(np.mean((np.linalg.norm(points, axis=1) - true_radius) ** 2)))


@pytest.mark.parametrize("ratio", [0.2, 0.5, 1.0])
def test_noise_estimate_recovers_the_true_noise(ratio):
    """The noise estimate is within 15 % of the true standard deviation along the normals."""
    vertices, faces = icosphere(4)
    edges = edges_of(faces)
    noisy, sigma = with_normal_noise(vertices, ratio, edges)
    amount = core.choose_amount(noisy, edges)
    assert 0.85 < amount.sigma / sigma < 1.15
    assert amount.alpha == 0.0 and amount.beta == 0.6
    assert 1 <= amount.iterations <= noise.MAX_ITERATIONS


@pytest.mark.slow
def test_more_noise_more_iterations():
    vertices, faces = bumpy_sphere()
    edges = edges_of(faces)
    chosen = [
        core.choose_amount(with_normal_noise(vertices, ratio, edges)[0], edges).iterations for ratio in (0.05, 0.2, 0.8)
    ]
    assert chosen[0] < chosen[1] < chosen[2]


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [0.2, 0.8])
def test_chosen_amount_is_near_the_best_number_of_iterations(ratio):
    """Within 10 % of the least error any number of iterations (alpha 0, beta 0.6) reaches, and better
    than the fixed amount alpha 0.1, 10 iterations."""
    vertices, faces = bumpy_sphere()
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, ratio, edges, seed=3)
    amount = core.choose_amount(noisy, edges)
    operator = core.umbrella_operator(edges, len(noisy))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        run = core.Smoothing(noisy, None, alpha=0.0, beta=0.6, iterations=200, operator=operator)
        errors = []
        for _ in range(200):
            run.advance(1)
            errors.append(surface_error(run.result().positions, vertices))
    chosen = errors[amount.iterations - 1]
    fixed = surface_error(core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=10), vertices)
    assert chosen <= 1.1 * min(errors)
    assert chosen < fixed


def test_light_noise_is_found_and_smoothed_within_its_radius():
    """Noise of 0.05 edge lengths, below core.mesh.noise's threshold: a half step takes most of it away,
    so it is found as light noise; the default removes more of it than the fixed HC default does, and no
    vertex moves farther than LIGHT_DEVIATIONS robust estimates."""
    vertices, faces = bumpy_sphere()
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, 0.05, edges, seed=3)
    chooser = core.AmountChooser(noisy, edges)
    list(chooser.steps())
    found = chooser.noise
    assert chooser.amount.noise_found and found.light.all()
    assert 0.0 < found.sigma[0] < core.mesh.noise.NOISE_THRESHOLD * found.edge_length[0]
    result, report = core.smooth_mesh(noisy, edges, faces=faces, return_report=True)
    fixed = core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=10)
    assert surface_error(result, vertices) < surface_error(fixed, vertices) < surface_error(noisy, vertices)
    moved = np.linalg.norm(result - noisy, axis=1)
    assert report.iterations > 0
    assert moved.max() <= core.mesh.noise.LIGHT_DEVIATIONS * found.sigma[0] * (1 + 1e-9)


def test_detail_below_the_threshold_moves_within_a_share_of_the_size(monkeypatch):
    """Bumps three to four edges wide, no noise: the estimate reads them as 0.056 edge lengths, below the
    threshold, and a half step keeps most of them: no noise found. What the default would take away is
    the bumps (its residual correlates between neighbours, core.mesh.collapse): the part is left as it was.
    Without that test it smooths them, but no vertex moves farther than QUIET_SHARE of the size."""
    vertices, faces = icosphere(4)
    vertices = vertices * (1.0 + 0.08 * np.prod(np.sin(12 * vertices), axis=1))[:, None]
    edges = edges_of(faces)
    amount = core.choose_amount(vertices, edges)
    assert not amount.noise_found and 0.03 < amount.ratio < core.mesh.noise.NOISE_THRESHOLD
    result, report = core.smooth_mesh(vertices, edges, faces=faces, return_report=True)
    assert report.iterations > 0 and report.held_parts == 1 and np.array_equal(result, vertices)
    monkeypatch.setattr(core.mesh.collapse, "SMOOTH_RESIDUAL", np.inf)
    result, report = core.smooth_mesh(vertices, edges, faces=faces, return_report=True)
    diagonal = np.linalg.norm(np.ptp(vertices, axis=0))
    moved = np.linalg.norm(result - vertices, axis=1)
    assert report.iterations > 0 and 0.0 < moved.max() <= core.mesh.noise.QUIET_SHARE * diagonal * (1 + 1e-9)


def test_scale_position_and_orientation_do_not_change_the_choice():
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, 0.4, edges)
    reference = core.choose_amount(noisy, edges)
    rotation, _ = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))
    for scale in (1e-4, 1e5):
        moved = noisy @ rotation.T * scale + np.array([3.0, -7.0, 11.0]) * scale
        amount = core.choose_amount(moved, edges)
        assert amount.iterations == reference.iterations
        assert amount.sigma == pytest.approx(reference.sigma * scale, rel=1e-6)
        assert amount.edge_length == pytest.approx(reference.edge_length * scale, rel=1e-9)


def test_deterministic_and_input_untouched():
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, 0.3, edges)
    noisy32 = noisy.astype(np.float32)
    copy = noisy32.copy()
    first, second = core.choose_amount(noisy32, edges), core.choose_amount(noisy32, edges)
    assert first == second
    assert np.array_equal(noisy32, copy)
    assert core.choose_amount(noisy, edges).iterations == first.iterations


def test_no_warning_and_operator_reused():
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, 0.3, edges)
    operator = core.umbrella_operator(edges, len(noisy))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        amount = core.choose_amount(noisy, operator=operator)
    assert amount == core.choose_amount(noisy, edges)


def test_fixed_vertices():
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, 0.3, edges)
    assert core.choose_amount(noisy, edges, fixed=np.ones(len(noisy), bool)).iterations == 0
    half = noisy[:, 2] > 0
    amount = core.choose_amount(noisy, edges, fixed=half)
    assert amount.iterations >= 1 and amount.sigma > 0


def test_lines_and_tiny_meshes():
    """Without surface (a polyline: no vertex has three neighbours) the whole residual decides."""
    t = np.linspace(0, 4 * np.pi, 400)
    line = np.stack([np.cos(t), np.sin(t), t / 10], 1) + np.random.default_rng(0).normal(0, 0.01, (400, 3))
    edges = np.stack([np.arange(399), np.arange(1, 400)], 1)
    amount = core.choose_amount(line, edges)
    assert amount.iterations >= 1 and amount.sigma > 0
    triangle = core.choose_amount(np.eye(3), np.array([[0, 1], [1, 2], [2, 0]]))
    assert triangle.iterations >= 0


def test_bad_input():
    vertices, faces = icosphere(2)
    edges = edges_of(faces)
    with pytest.raises(ValueError):
        core.choose_amount(vertices[:, :2], edges)
    with pytest.raises(ValueError):
        core.choose_amount(vertices, edges, beta=1.5)
    with pytest.raises(ValueError):
        core.choose_amount(vertices, operator=core.umbrella_operator(edges, len(vertices) + 1))


@pytest.mark.parametrize("ratio", [0.1, 0.5, 1.0])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_choice_hands_back_the_run_it_made_bit_for_bit(ratio, dtype):
    """The data run passes through the chosen amount: its state there is the result of a fresh run."""
    vertices, faces = bumpy_sphere()
    edges = edges_of(faces)
    noisy = with_normal_noise(vertices, ratio, edges)[0].astype(dtype)
    fixed = np.zeros(len(noisy), dtype=bool)
    fixed[::17] = True
    chooser = core.AmountChooser(noisy, edges, beta=0.6, fixed=fixed)
    for _ in chooser.steps():
        pass
    kept = chooser.result()
    assert kept is not None  # the choice stayed where the run last kept its state
    with warnings.catch_warnings():  # alpha 0 on purpose, as the chooser runs it
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        amount = chooser.amount
        fresh = core.hc_smooth(noisy, edges, alpha=0.0, beta=amount.beta, iterations=amount.iterations, fixed=fixed)
    assert kept.dtype == dtype and np.array_equal(kept.view(np.uint8), fresh.view(np.uint8))


@pytest.mark.parametrize("ratio, seed, taken", [(0.15, 0, True), (0.12, 0, False), (0.3, 0, False)])
def test_light_noise_is_chosen_again_on_gentler_steps_where_they_smooth_more(monkeypatch, ratio, seed, taken):
    """Where whole steps pick at most FINE_MAX iterations, the choice is made again with beta FINE_BETA
    and taken only where it smooths a low frequency more (k' (1 - 0.75) > k (1 - 0.6)); the result
    handed back is then that run, bit for bit."""
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    noisy = with_normal_noise(vertices, ratio, edges, seed)[0]
    with monkeypatch.context() as patch:
        patch.setattr(noise, "FINE_MAX", 0)
        whole = core.choose_amount(noisy, edges, beta=0.6)
        gentle = core.choose_amount(noisy, edges, beta=noise.FINE_BETA)
    chooser = core.AmountChooser(noisy, edges, beta=0.6)
    for _ in chooser.steps():
        pass
    amount = chooser.amount
    eligible = whole.iterations <= noise.FINE_MAX
    assert taken == (eligible and gentle.iterations * 0.25 > whole.iterations * 0.4)
    assert (amount.beta, amount.iterations) == ((0.75, gentle.iterations) if taken else (0.6, whole.iterations))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        fresh = core.hc_smooth(noisy, edges, alpha=0.0, beta=amount.beta, iterations=amount.iterations)
    assert np.array_equal(chooser.result(), fresh)
    # A beta at least as gentle as FINE_BETA is never chosen again.
    assert core.choose_amount(noisy, edges, beta=0.8).beta == 0.8


def test_nothing_ran_hands_back_the_input():
    vertices, faces = icosphere(2)
    noisy, _ = with_normal_noise(vertices, 0.5, edges_of(faces))
    chooser = core.AmountChooser(noisy, edges_of(faces), fixed=np.ones(len(vertices), dtype=bool))
    for _ in chooser.steps():
        pass
    assert chooser.amount.iterations == 0 and chooser.amount.noise_found
    result = chooser.result()
    assert np.array_equal(result, noisy) and result is not noisy


def noisy_torus_grid(around=500, across=100, ratio=0.4, seed=0):
    """A triangulated torus grid (every vertex of degree 6: the same connectivity everywhere) with
    Gaussian noise of ``ratio`` edge lengths on every coordinate, and its edges."""
    a, b = np.meshgrid(np.arange(around) * 2 * np.pi / around, np.arange(across) * 2 * np.pi / across, indexing="ij")
    ring = 1.0 + 0.35 * np.cos(b)
    vertices = np.stack([ring * np.cos(a), ring * np.sin(a), 0.35 * np.sin(b)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(around), np.arange(across), indexing="ij")
    corner = [((i + di) % around) * across + (j + dj) % across for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1))]
    faces = np.concatenate(
        [np.stack([corner[0], corner[1], corner[2]], -1), np.stack([corner[0], corner[2], corner[3]], -1)]
    )
    edges = edges_of(faces.reshape(-1, 3))
    noise_size = ratio * edge_length(vertices, edges)
    return vertices + np.random.default_rng(seed).normal(0.0, noise_size, vertices.shape), edges


@pytest.mark.slow
def test_patches_estimate_the_trace_and_the_amount_of_the_whole_mesh(monkeypatch):
    """On big meshes the runs go on patches; their inner vertices give the whole mesh's t(k), and about
    the same amount: GCV is flat near its minimum, and the residual is read on other sample vertices, so
    the choice may move to the next checkpoint. The smoothing then runs on the whole mesh (no result
    from the choice). (Patches made to start small here, so that a test-sized mesh gets them.)"""
    noisy, edges = noisy_torus_grid()
    fixed = np.zeros(len(noisy), dtype=bool)
    fixed[::17] = True

    def choose():
        chooser = core.AmountChooser(noisy, edges, beta=0.6, fixed=fixed)
        for _ in chooser.steps():
            pass
        return chooser

    whole = choose()
    assert whole.runs[0].smoothing.shape[0] == len(noisy) and whole.trace_count == np.count_nonzero(~fixed)
    monkeypatch.setattr(noise, "PATCH_FROM", 0)
    monkeypatch.setattr(noise, "PATCH_RINGS", 30)
    monkeypatch.setattr(noise, "PATCH_MARGIN", 12)
    patched = choose()
    assert patched.runs[0].smoothing.shape[0] < 0.5 * len(noisy)  # the probes ran on patches
    assert patched.trace_count < patched.runs[0].smoothing.shape[0]  # ... read on their inner vertices
    assert patched.traces.keys() == whole.traces.keys()
    for k, t in whole.traces.items():  # within 0.002: GCV's 1 / (1 - t)^2 moves by under TOLERANCE
        assert patched.traces[k] == pytest.approx(t, abs=0.002)
    checkpoints = list(noise._checkpoints(noise.MAX_ITERATIONS))
    assert abs(checkpoints.index(patched.amount.iterations) - checkpoints.index(whole.amount.iterations)) <= 1
    assert patched.amount.sigma == pytest.approx(whole.amount.sigma, rel=0.05)
    assert whole.result() is not None and patched.result() is None


def test_sigma_is_capped_by_the_robust_estimate_on_coarse_meshes():
    """On Blender's cone (33 vertices) with light noise GCV reads the shape as noise (~4x the truth); the
    amount's sigma is at most ROBUST_SIGMAS times core.mesh.noise's estimate, within 2x of the truth."""
    from bench.primitives import PRIMITIVES, with_noise

    cone, sigma = with_noise(PRIMITIVES["cone_ngon"](), 0.1, "isotropic")
    chooser = core.AmountChooser(cone.positions, cone.edges)
    for _ in chooser.steps():
        pass
    assert chooser.amount.noise_found
    assert chooser.amount.sigma == pytest.approx(noise.ROBUST_SIGMAS * chooser.noise.level())
    assert 0.5 * sigma < chooser.amount.sigma < 3.0 * sigma


def test_work_budget_and_patches_are_parameters():
    """``work_budget`` cuts the chosen iterations to budget / vertices (math.inf: no cut, the default's
    choice on a mesh this small); ``patch_from`` at or below the movable vertices runs the choice on
    patches, which hand back no result."""
    vertices, faces = icosphere(4)
    edges = edges_of(faces)
    noisy, _ = with_normal_noise(vertices, 0.5, edges)
    uncut = core.choose_amount(noisy, edges, work_budget=math.inf)
    assert uncut == core.choose_amount(noisy, edges) and uncut.iterations > 3 and not uncut.capped
    cut = core.choose_amount(noisy, edges, work_budget=3 * len(noisy))
    assert cut.iterations == 3 and cut.capped
    # Once GCV wants more than the budget allows the choice stops: the checkpoint after 14 is 16.
    cut = core.choose_amount(noisy, edges, work_budget=14 * len(noisy))
    assert (cut.iterations, cut.explored, cut.capped) == (14, 16, True)
    assert cut.sigma == pytest.approx(uncut.sigma, rel=0.05)
    whole = core.AmountChooser(noisy, edges)
    patched = core.AmountChooser(noisy, edges, patch_from=1)
    for chooser in (whole, patched):
        for _ in chooser.steps():
            pass
    assert whole.data is not None and patched.data is None


def test_held_parts_are_a_parameter():
    """``hold_parts=False``: the part the default gives back (the bumps of the test above) is smoothed."""
    vertices, faces = icosphere(4)
    vertices = vertices * (1.0 + 0.08 * np.prod(np.sin(12 * vertices), axis=1))[:, None]
    edges = edges_of(faces)
    held, report = core.smooth_mesh(vertices, edges, faces=faces, return_report=True)
    assert report.held_parts == 1 and np.array_equal(held, vertices)
    smoothed, report = core.smooth_mesh(vertices, edges, faces=faces, return_report=True, hold_parts=False)
    assert report.held_parts == 0 and report.iterations > 0 and not np.array_equal(smoothed, vertices)


@pytest.mark.parametrize("threads", [1, 2])
def test_runs_beside_each_other_give_what_they_give_alone(monkeypatch, threads):
    """The Automatic Amount's runs on patches go side by side, each on one thread (``run_beside``), with
    threads off one after another: the choice is the same bit for bit, and with threads on the runs
    did run on two threads."""
    noisy, edges = noisy_torus_grid()
    ran_on = set()
    advance = noise._Run.advance

    def recorded(run, count):
        ran_on.add(threading.get_ident())
        advance(run, count)

    monkeypatch.setattr(noise._Run, "advance", recorded)
    monkeypatch.setattr(parallel, "thread_count", lambda: threads)
    chooser = core.AmountChooser(noisy, edges, patch_from=1)
    for _ in chooser.steps():
        pass
    monkeypatch.setattr(parallel, "thread_count", lambda: 1)
    alone = core.AmountChooser(noisy, edges, patch_from=1)
    for _ in alone.steps():
        pass
    assert chooser.amount == alone.amount and chooser.traces == alone.traces
    assert (len(ran_on) > 1) == (threads > 1)  # threads on: more than this one ran the runs
