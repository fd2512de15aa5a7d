"""Section 5 of the paper: what converges, what oscillates, and where the limits lie."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import small_meshes as sm
from oracles import hc_iteration_matrix, spectral_radius, umbrella_matrix

import core
from core.convergence import convergence_lines


def random_connected_graph(n, extra, seed):
    rng = np.random.default_rng(seed)
    tree = np.stack([np.arange(1, n), rng.integers(0, np.arange(1, n))], axis=1)  # a random spanning tree
    more = rng.integers(0, n, size=(extra, 2))
    return np.concatenate([tree, more])


@pytest.mark.parametrize("seed", range(6))
def test_hc_iteration_matrix_contracts_inside_the_region(seed):
    edges = random_connected_graph(12, 10, seed)
    operator = core.umbrella_operator(edges, 12)
    for alpha in (0.01, 0.1, 0.5, 0.9, 1.0):
        for beta in (0.51, 0.6, 0.8, 1.0):
            assert core.in_convergence_region(alpha, beta)
            assert spectral_radius(hc_iteration_matrix(operator, alpha, beta)) < 1.0


@pytest.mark.parametrize("seed", range(3))
def test_hc_without_pull_to_the_original_does_not_contract(seed):
    """alpha = 0: T has eigenvalue 1 (constants), and p(1) = 1, so H has spectral radius 1."""
    operator = core.umbrella_operator(random_connected_graph(10, 8, seed), 10)
    assert not core.in_convergence_region(0.0, 0.6)
    assert spectral_radius(hc_iteration_matrix(operator, 0.0, 0.6)) == pytest.approx(1.0, abs=1e-9)


def test_paper_example_polynomial_exceeds_one_off_the_real_axis():
    """Section 5: for beta = 0.6, alpha = 0.1, |p(i)| is about 1.2, so real eigenvalues of T matter."""
    alpha, beta = 0.1, 0.6
    value = -(1 - beta) * 1j**2 + (2 - alpha) * (1 - beta) * 1j + (1 - alpha) * beta
    assert abs(value) == pytest.approx(1.2, abs=0.01)
    x = np.linspace(-1, 1, 2001)  # but on the real interval [-1, 1], |p| < 1
    assert np.abs(-(1 - beta) * x**2 + (2 - alpha) * (1 - beta) * x + (1 - alpha) * beta).max() < 1


def test_hc_converges_to_the_fixed_point_of_theorem_5_2():
    positions, faces = sm.uv_sphere(6, 8)
    positions, edges = sm.noisy(positions, 0.1), sm.edges_of(faces)
    alpha, beta = 0.3, 0.7
    operator = core.umbrella_operator(edges, len(positions))
    t = umbrella_matrix(operator).toarray()
    e = np.eye(len(positions))
    h = hc_iteration_matrix(operator, alpha, beta)
    constant = (alpha * beta * e + alpha * (1 - beta) * t) @ positions  # no fixed vertices: r = 0
    limit = np.linalg.solve(np.eye(len(positions)) - h, constant)
    for mode in core.MODES:
        result = core.hc_smooth(positions, edges, alpha=alpha, beta=beta, iterations=400, mode=mode)
        if mode == "simultaneous":
            np.testing.assert_allclose(result, limit, atol=1e-9)
        steps = [core.hc_smooth(positions, edges, alpha=alpha, beta=beta, iterations=k, mode=mode) for k in (50, 51)]
        assert np.abs(steps[1] - steps[0]).max() < 1e-6  # settled


def test_two_vertex_mesh_oscillates_under_plain_simultaneous_laplacian():
    """Section 3.3: one edge {i, j}: the simultaneous Laplacian swaps the two points forever."""
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])
    edges = np.array([[0, 1]])
    one = core.laplacian_smooth(positions, edges, iterations=1)
    two = core.laplacian_smooth(positions, edges, iterations=2)
    many = core.laplacian_smooth(positions, edges, iterations=101)
    assert np.array_equal(one, positions[::-1])
    assert np.array_equal(two, positions)
    assert np.array_equal(many, positions[::-1])


def test_two_vertex_mesh_converges_with_the_original_point():
    """Section 3.3: including o_i with alpha > 0 forces convergence, to p = alpha o + (1 - alpha) T p."""
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])
    edges = np.array([[0, 1]])
    alpha = 0.25
    t = np.array([[0.0, 1.0], [1.0, 0.0]])
    limit = np.linalg.solve(np.eye(2) - (1 - alpha) * t, alpha * positions)
    result = core.laplacian_smooth(positions, edges, variant="original", alpha=alpha, iterations=200)
    np.testing.assert_allclose(result, limit, atol=1e-12)
    assert not np.allclose(limit[0], limit[1])  # a non-trivial limit, not a single point


@pytest.mark.slow
def test_simultaneous_and_sequential_laplacian_have_the_same_limit():
    """Section 3.1/5: both are iterative solvers of one linear system (here: boundary fixed, a harmonic patch)."""
    positions, faces = sm.grid(7, 6)
    positions = sm.noisy(positions, 0.2, seed=4)
    edges = sm.edges_of(faces)
    n = len(positions)
    x, y = positions[:, 0], positions[:, 1]
    boundary = (
        np.isclose(x, x.min(), atol=0.5)
        | np.isclose(x, x.max(), atol=0.5)
        | np.isclose(y, y.min(), atol=0.5)
        | np.isclose(y, y.max(), atol=0.5)
    )
    limits = {
        mode: core.laplacian_smooth(positions, edges, iterations=3000, mode=mode, fixed=boundary) for mode in core.MODES
    }
    # The exact limit: (I - T) p = 0 on movable rows, p = o on fixed ones.
    t = umbrella_matrix(core.umbrella_operator(edges, n))
    movable = ~boundary
    system = sp.identity(n, format="csr") - sp.diags(movable.astype(float)) @ t
    exact = spla.spsolve(system.tocsc(), positions * boundary[:, None])
    exact[boundary] = positions[boundary]
    for mode in core.MODES:
        np.testing.assert_allclose(limits[mode], exact, atol=1e-9)
    assert np.abs(exact - positions).max() > 0.05


def test_plain_laplacian_shrinks_a_closed_mesh_towards_a_point_and_hc_does_not():
    positions, faces = sm.uv_sphere(10, 16)
    noisy, edges = sm.noisy(positions, 0.02), sm.edges_of(faces)
    lap = core.laplacian_smooth(noisy, edges, iterations=200)
    hc = core.hc_smooth(noisy, edges, alpha=0.1, beta=0.6, iterations=200)
    lap_change = core.measure_change(noisy, lap, faces=np.array(faces))
    hc_change = core.measure_change(noisy, hc, faces=np.array(faces))
    assert lap_change.volume_change < -0.9
    assert abs(hc_change.volume_change) < 0.1


def test_hc_outside_the_region_warns_but_runs():
    positions, faces = sm.octahedron()
    edges = sm.edges_of(faces)
    with pytest.warns(core.ConvergenceWarning, match="beta"):
        result = core.hc_smooth(sm.noisy(positions), edges, alpha=0.2, beta=0.3, iterations=3)
    assert np.isfinite(result).all()
    assert core.convergence_message(0.2, 0.6) is None
    assert "alpha" in core.convergence_message(0.0, 0.6)


def test_panel_lines_follow_the_paper():
    # The short lines panels show (operators/draw.py): the same region as convergence_message, section 5's verdicts.
    for alpha in np.linspace(0, 1, 11):
        for beta in np.linspace(0, 1, 11):
            converges, lines = convergence_lines("hc", alpha, beta)
            assert converges == (alpha > 0 and beta > 0.5) == (core.convergence_message(alpha, beta) is None)
            assert lines and ("Outside the convergence region:" in lines) == (not converges)
            assert convergence_lines("original", alpha, beta)[0] == (alpha > 0)  # to a shrunken shape
            assert not convergence_lines("plain", alpha, beta)[0] and not convergence_lines("central", alpha, beta)[0]
    assert "\u03b2 = 0.4 is not above 0.5" in convergence_lines("hc", 0.1, 0.4)[1]


def test_smooth_at_its_defaults_is_inside_the_convergence_region():
    """core.smooth and core.Smoothing left at their defaults run HC inside Theorem 5.2's region: no
    ConvergenceWarning, and the defaults are the ones the mesh pipeline documents."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    with warnings.catch_warnings():
        warnings.simplefilter("error", core.ConvergenceWarning)
        result = core.smooth(positions, edges, iterations=3)
        core.Smoothing(positions, edges, iterations=3)
    assert result.iterations == 3
    assert core.in_convergence_region(core.DEFAULT_ALPHA, core.DEFAULT_BETA)
    with pytest.warns(core.ConvergenceWarning):  # the warning this test relies on is there off the region
        core.smooth(positions, edges, alpha=0.0, beta=0.5, iterations=3)
