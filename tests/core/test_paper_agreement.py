"""Every smoother, both modes, agrees with the per-vertex loop written from the paper, to rounding."""

import numpy as np
import pytest
import small_meshes as sm
from paper_reference import smooth_loop

import core


def _mesh_cases():
    sphere = sm.uv_sphere(5, 7)
    cases = {
        "closed octahedron": sm.octahedron(),
        "closed sphere": sphere,
        "open grid with boundary": sm.grid(5, 4),
        "quads": sm.cube_quads(),
        "n-gons": sm.pentagonal_prism(),
        "disconnected parts": sm.combined(sm.octahedron(), sm.grid(3, 3), sm.cube_quads()),
        "isolated vertices": sm.with_isolated(*sm.octahedron()),
    }
    for name, (positions, faces) in cases.items():
        yield name, sm.noisy(positions, seed=len(name)), sm.edges_of(faces)


MESHES = list(_mesh_cases())
METHODS = [("plain", 0.0, 0.5), ("central", 0.3, 0.5), ("original", 0.2, 0.5), ("hc", 0.1, 0.6), ("hc", 0.0, 0.5)]


@pytest.mark.parametrize("name,positions,edges", MESHES, ids=[m[0] for m in MESHES])
@pytest.mark.parametrize("method,alpha,beta", METHODS, ids=[f"{m}-a{a}-b{b}" for m, a, b in METHODS])
@pytest.mark.parametrize("mode", core.MODES)
@pytest.mark.parametrize("fixed_kind", ["none", "some"])
def test_matches_plain_loop(name, positions, edges, method, alpha, beta, mode, fixed_kind):
    fixed = [0, len(positions) // 2] if fixed_kind == "some" else []
    expected = np.array(
        smooth_loop(positions, edges, method=method, alpha=alpha, beta=beta, iterations=4, mode=mode, fixed=fixed)
    )
    with (
        np.errstate(all="raise"),
        pytest.warns(core.ConvergenceWarning) if (method, alpha) == ("hc", 0.0) else _no_warning(),
    ):
        result = core.smooth(
            positions,
            edges,
            method=method,
            alpha=alpha,
            beta=beta,
            iterations=4,
            mode=mode,
            fixed=np.array(fixed, dtype=np.int64),
        )
    diagonal = np.linalg.norm(np.ptp(positions, axis=0))
    assert result.iterations == 4
    np.testing.assert_allclose(result.positions, expected, rtol=0, atol=1e-12 * diagonal)
    # the reference really moved something, so the comparison is not vacuous
    assert np.abs(expected - positions).max() > 1e-3


class _no_warning:
    def __enter__(self):
        import warnings

        self._catch = warnings.catch_warnings()
        self._catch.__enter__()
        warnings.simplefilter("error", core.ConvergenceWarning)

    def __exit__(self, *exc):
        return self._catch.__exit__(*exc)


def test_public_wrappers_equal_smooth():
    positions, faces = sm.uv_sphere(6, 9)
    positions, edges = sm.noisy(positions), sm.edges_of(faces)
    for mode in core.MODES:
        hc = core.hc_smooth(positions, edges, alpha=0.2, beta=0.7, iterations=5, mode=mode)
        via = core.smooth(positions, edges, method="hc", alpha=0.2, beta=0.7, iterations=5, mode=mode)
        assert np.array_equal(hc, via.positions)
        for variant in ("plain", "central", "original"):
            lap = core.laplacian_smooth(positions, edges, variant=variant, alpha=0.3, iterations=3, mode=mode)
            via = core.smooth(positions, edges, method=variant, alpha=0.3, iterations=3, mode=mode)
            assert np.array_equal(lap, via.positions)


def test_float32_in_float32_out_close_to_float64():
    positions, faces = sm.uv_sphere(8, 12)
    positions, edges = sm.noisy(positions), sm.edges_of(faces)
    for mode in core.MODES:
        exact = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=10, mode=mode)
        single = core.hc_smooth(positions.astype(np.float32), edges, alpha=0.1, beta=0.6, iterations=10, mode=mode)
        assert single.dtype == np.float32
        np.testing.assert_allclose(single, exact, atol=1e-5)


def test_sequential_really_uses_updated_neighbours():
    """On a path 0-1-2, sequential moves vertex 1 using the new position of 0, unlike simultaneous."""
    positions = np.array([[0.0, 0, 0], [1.0, 0, 0], [5.0, 0, 0]])
    edges = np.array([[0, 1], [1, 2]])
    sim = core.laplacian_smooth(positions, edges, iterations=1, mode="simultaneous")
    seq = core.laplacian_smooth(positions, edges, iterations=1, mode="sequential")
    assert sim[1, 0] == 2.5 and seq[0, 0] == 1.0 and seq[1, 0] == 3.0 and seq[2, 0] == 3.0


def test_sequential_order_is_increasing_vertex_index():
    """Relabelling the vertices changes the sequential result (it depends on the order), not the simultaneous."""
    positions, faces = sm.grid(4, 4)
    positions, edges = sm.noisy(positions), sm.edges_of(faces)
    perm = np.random.default_rng(3).permutation(len(positions))
    inverse = np.argsort(perm)
    relabelled_edges = inverse[edges]
    for mode, same in (("simultaneous", True), ("sequential", False)):
        a = core.laplacian_smooth(positions, edges, iterations=2, mode=mode)
        b = core.laplacian_smooth(positions[perm], relabelled_edges, iterations=2, mode=mode)[inverse]
        assert np.allclose(a, b, atol=1e-12) == same


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_triangular_fallback_gives_the_same_result(monkeypatch, dtype):
    """The public spsolve_triangular path (used if SciPy's private kernel is missing or changes) calls
    the same SuperLU kernel, so it gives the fast path's bits."""
    from core import triangular

    positions, faces = sm.uv_sphere(6, 8)
    positions, edges = sm.noisy(positions).astype(dtype), sm.edges_of(faces)
    fast = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=5, mode="sequential")
    monkeypatch.setattr(triangular, "_gstrs", None)
    slow = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=5, mode="sequential")
    assert slow.dtype == dtype
    assert np.array_equal(slow.view(np.uint8), fast.view(np.uint8))


def test_a_changed_private_kernel_switches_to_the_public_path(monkeypatch):
    """If SciPy's private gstrs changes its signature, the solver notices once and stays on the public path."""
    from core import triangular

    positions, faces = sm.uv_sphere(6, 8)
    positions, edges = sm.noisy(positions), sm.edges_of(faces)
    expected = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode="sequential")
    calls = []

    def changed(*args):
        calls.append(len(args))
        raise TypeError("gstrs() takes different arguments now")

    monkeypatch.setattr(triangular, "_gstrs", changed)
    got = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode="sequential")
    assert np.array_equal(got, expected)
    assert len(calls) == 1  # tried once per solver, then the public path for every iteration
