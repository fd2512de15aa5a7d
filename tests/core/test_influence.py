"""Painted influence: each vertex takes its weight times the paper's move every iteration.

The oracle is the paper's loop (tests/core/paper_reference.py) extended the same way, one iteration
at a time: q_i + w_i (p_i - q_i); weight 0 stays bit-identical, weight 1 is the paper's step.
"""

import warnings

import numpy as np
import paper_reference
import pytest
import small_meshes as sm

import core

POSITIONS, FACES = sm.uv_sphere(6, 10)
NOISY = sm.noisy(POSITIONS, 0.05)
EDGES = sm.edges_of(FACES)


def weighted_loop(positions, edges, weights, *, method, alpha, beta, iterations, mode, fixed=()):
    """The paper's loop (as tests/core/paper_reference.py), with o the input throughout and each
    iteration's result blended per vertex: q_i + w_i (p_i - q_i)."""
    n = len(positions)
    adj = paper_reference.adjacency(n, edges)
    frozen = set(int(i) for i in fixed) | {i for i in range(n) if not adj[i]}
    o = [[float(c) for c in p] for p in positions]
    q = [list(v) for v in o]
    for _ in range(iterations):
        new = [list(v) for v in q]
        for i in range(n):  # the Laplacian pass; sequential reads the neighbours already updated
            if i in frozen:
                continue
            source = new if mode == "sequential" else q
            avg = [sum(source[j][k] for j in adj[i]) / len(adj[i]) for k in range(3)]
            if method in ("plain", "hc"):
                new[i] = avg
            elif method == "central":
                new[i] = [alpha * q[i][k] + (1 - alpha) * avg[k] for k in range(3)]
            else:
                new[i] = [alpha * o[i][k] + (1 - alpha) * avg[k] for k in range(3)]
        if method == "hc":
            b = {
                i: [new[i][k] - (alpha * o[i][k] + (1 - alpha) * q[i][k]) for k in range(3)]
                for i in range(n)
                if i not in frozen
            }
            zero = [0.0, 0.0, 0.0]
            for i in range(n):
                if i not in frozen:
                    sum_b = [sum(b.get(j, zero)[k] for j in adj[i]) for k in range(3)]
                    new[i] = [new[i][k] - (beta * b[i][k] + (1 - beta) / len(adj[i]) * sum_b[k]) for k in range(3)]
        q = [[q[i][k] + weights[i] * (new[i][k] - q[i][k]) for k in range(3)] for i in range(n)]
    return np.array(q)


WEIGHTS = np.random.default_rng(4).choice([0.0, 0.25, 0.5, 1.0], size=len(NOISY))


@pytest.mark.parametrize("method", core.METHODS)
@pytest.mark.parametrize("mode", core.MODES)
def test_weighted_step_equals_the_paper_loop_extended(method, mode):
    options = dict(method=method, alpha=0.2, beta=0.7, iterations=4, mode=mode)
    got = core.smooth(NOISY, EDGES, influence=WEIGHTS, fixed=[3], **options).positions
    expected = weighted_loop(NOISY, EDGES, WEIGHTS, fixed=[3], **options)
    np.testing.assert_allclose(got, expected, atol=1e-12)


@pytest.mark.parametrize("mode", core.MODES)
def test_weight_zero_is_bit_identical_and_weight_one_is_the_paper_step(mode):
    options = dict(alpha=0.1, beta=0.6, iterations=5, mode=mode)
    ones = core.hc_smooth(NOISY, EDGES, influence=np.ones(len(NOISY)), **options)
    assert np.array_equal(ones, core.hc_smooth(NOISY, EDGES, **options))
    start = NOISY.copy()
    start[WEIGHTS == 0, 0] = -0.0  # old + 0 * move would turn these into +0.0
    got = core.hc_smooth(start, EDGES, influence=WEIGHTS, **options)
    still = WEIGHTS == 0
    assert np.array_equal(got[still].view(np.uint64), start[still].view(np.uint64))
    assert np.abs(got[WEIGHTS == 0.5] - start[WEIGHTS == 0.5]).max() > 1e-3  # partial weights do move


def test_half_influence_moves_half_as_far_in_one_iteration():
    full = core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=1)
    half = core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=1, influence=np.full(len(NOISY), 0.5))
    np.testing.assert_allclose(half - NOISY, 0.5 * (full - NOISY), atol=1e-15)


@pytest.mark.parametrize(
    "influence, message",
    [
        (np.ones(3), "influence must be"),
        (np.full(len(NOISY), 1.5), "between 0 and 1, got 1.5 at vertex 0"),
        (np.where(np.arange(len(NOISY)) == 2, np.nan, 0.5), "at vertex 2"),
        (np.array(["a"] * len(NOISY)), "influence must be"),
    ],
)
def test_bad_influence_is_refused(influence, message):
    with pytest.raises(ValueError, match=message):
        core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=1, influence=influence)


def test_influence_with_renumbering_and_float32():
    rng = np.random.default_rng(9)
    order = rng.permutation(len(NOISY))
    inverse = np.argsort(order)
    shuffled_edges = inverse[EDGES]
    points = NOISY[order].astype(np.float32)
    weights = WEIGHTS[order]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = core.hc_smooth(points, shuffled_edges, alpha=0.1, beta=0.6, iterations=3, influence=weights)
    expected = core.hc_smooth(NOISY.astype(np.float32), EDGES, alpha=0.1, beta=0.6, iterations=3, influence=WEIGHTS)
    np.testing.assert_allclose(got, expected[order], atol=2e-6)
