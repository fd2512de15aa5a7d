"""core.MeshSmoother / core.smooth_mesh: the mesh pipeline every route runs (choose, smooth, keep volume)."""

import warnings

import numpy as np
import pytest
from test_mesh_amount import bumpy_sphere, edges_of, with_normal_noise

import core
from core.mesh import amount as mesh_amount
from core.slices import to_end


@pytest.fixture(scope="module")
def noisy_sphere():
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    return with_normal_noise(vertices, 0.5, edges, seed=3)[0], edges, faces


def paper_hc(positions, edges, **numbers):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        return core.hc_smooth(positions, edges, **numbers)


def test_automatic_amount_is_choose_smooth_restore(noisy_sphere):
    """The default run is choose_amount, that HC run (alpha 0), its moves kept across the surface
    (core.mesh.in_place) and the volume given back along the normals they were kept along, bit for bit."""
    noisy, edges, faces = noisy_sphere
    result, report = core.smooth_mesh(noisy, edges, faces=faces, return_report=True)
    amount = core.choose_amount(noisy, edges, beta=core.DEFAULT_BETA)
    assert report.amount == amount and report.alpha == 0.0 and report.iterations == amount.iterations > 1
    smoothed = paper_hc(noisy, edges, alpha=0.0, beta=amount.beta, iterations=amount.iterations)
    smoothed, normals = to_end(core.mesh.in_place.keep_in_place_steps(noisy, smoothed, faces, with_normals=True))
    restored, offsets = to_end(core.mesh.volume.restore_steps(noisy, smoothed, faces, normals=normals))
    assert np.array_equal(result, restored) and report.kept_in_place
    assert report.volume_offset == pytest.approx(np.abs(offsets).max()) and report.volume_offset > 0.0
    volumes = core.mesh.metrics.enclosed_volumes(faces, noisy, result)
    assert volumes[1] == pytest.approx(volumes[0], rel=1e-9)


def test_open_or_faceless_meshes_get_no_volume_restore(noisy_sphere):
    noisy, edges, faces = noisy_sphere
    without_faces, report = core.smooth_mesh(noisy, edges, return_report=True)
    assert report.volume_offset == 0.0
    amount = report.amount
    assert np.array_equal(
        without_faces, paper_hc(noisy, edges, alpha=0.0, beta=amount.beta, iterations=amount.iterations)
    )
    # One face less: the part is open.
    opened, report = core.smooth_mesh(noisy, edges, faces=faces[1:], return_report=True)
    kept = core.mesh.in_place.keep_in_place(noisy, without_faces, faces[1:])  # faces: Keep in Place, not restored
    # Away from the hole's ring: the plain projection (the hole's outline is kept as a curve: core.mesh.in_place)
    hole = np.isin(edges, faces[0]).any(axis=1)
    ring = np.zeros(len(noisy), dtype=bool)
    ring[edges[hole].ravel()] = True
    assert report.volume_offset == 0.0 and np.array_equal(opened[~ring], kept[~ring]) and report.kept_in_place


@pytest.mark.parametrize(
    "given, expected",
    [
        (dict(alpha=0.2, beta=0.7, iterations=7), dict(alpha=0.2, beta=0.7, iterations=7)),
        (dict(iterations=5), dict(alpha=core.DEFAULT_ALPHA, beta=core.DEFAULT_BETA, iterations=5)),
        (dict(alpha=0.3), dict(alpha=0.3, beta=core.DEFAULT_BETA, iterations=core.DEFAULT_ITERATIONS)),
    ],
)
def test_explicit_numbers_win(noisy_sphere, given, expected):
    """Alpha or iterations given: no Automatic Amount; the paper's HC with those numbers, bit for bit."""
    noisy, edges, faces = noisy_sphere
    result, report = core.smooth_mesh(noisy, edges, faces=faces, return_report=True, **given)
    assert report.amount is None and report.volume_offset == 0.0
    assert dict(alpha=report.alpha, beta=report.beta, iterations=report.iterations) == expected
    assert np.array_equal(result, paper_hc(noisy, edges, **expected))


def test_a_given_beta_is_never_changed_by_the_automatic_amount(monkeypatch):
    """On light noise the Automatic Amount may choose gentler steps; not when the caller gave beta."""
    vertices, faces = bumpy_sphere(3)
    edges = edges_of(faces)
    noisy = with_normal_noise(vertices, 0.15, edges, 0)[0]  # a case where the gentler steps are taken
    assert core.smooth_mesh(noisy, edges, return_report=True)[1].beta == mesh_amount.FINE_BETA
    result, report = core.smooth_mesh(noisy, edges, beta=0.6, return_report=True)
    assert report.beta == 0.6 and report.amount is not None
    assert np.array_equal(result, paper_hc(noisy, edges, alpha=0.0, beta=0.6, iterations=report.iterations))


@pytest.mark.parametrize("method", ["plain", "central", "original"])
def test_laplacian_variants_run_as_set(noisy_sphere, method):
    noisy, edges, _ = noisy_sphere
    result, report = core.smooth_mesh(noisy, edges, method=method, return_report=True)
    assert report.amount is None and report.iterations == core.DEFAULT_ITERATIONS
    expected = core.laplacian_smooth(
        noisy, edges, variant=method, alpha=core.DEFAULT_ALPHA, iterations=core.DEFAULT_ITERATIONS
    )
    assert np.array_equal(result, expected)


def test_slices_give_the_one_slice_result_and_progress_rises(noisy_sphere):
    noisy, edges, faces = noisy_sphere
    for options in (dict(), dict(alpha=0.1, beta=0.6, iterations=9), dict(mode="sequential", iterations=5)):
        whole = core.smooth_mesh(noisy, edges, faces=faces, **options)
        run = core.MeshSmoother(noisy, edges, faces=faces, **options)
        fractions = list(run.steps(chunk=2))
        assert np.array_equal(run.result, whole)
        assert fractions == sorted(fractions) and fractions[-1] == 1.0 and len(fractions) > 2


def test_cancel_leaves_the_input_and_raises(noisy_sphere):
    noisy, edges, faces = noisy_sphere
    before = noisy.copy()
    with pytest.raises(core.Cancelled):
        core.smooth_mesh(noisy, edges, faces=faces, progress=lambda fraction: fraction < 0.02)
    run = core.MeshSmoother(noisy, edges, faces=faces)
    steps = run.steps(chunk=1)
    next(steps)
    steps.close()  # abandoned: nothing is handed back
    assert run.result is None and np.array_equal(noisy, before)


@pytest.mark.parametrize("patches", [False, True])
def test_every_stage_yields_and_a_cancel_anywhere_hands_nothing_back(noisy_sphere, monkeypatch, patches):
    """The default as the add-on runs it (weld, border curve) yields between the passes of every stage:
    the welding and the faces' surface, the noise test, the choice (on the whole mesh, or on patches as
    big meshes have it), the smoothing and the volume restore (rounds of triangles). Abandoned after any
    slice, it hands nothing back and leaves the input as it was."""
    noisy, edges, faces = noisy_sphere
    before = noisy.copy()
    monkeypatch.setattr(core.mesh.volume, "BLOCK", 64)  # the restore in many rounds of triangles
    if patches:
        monkeypatch.setattr(mesh_amount, "PATCH_FROM", 100)
        monkeypatch.setattr(mesh_amount, "PATCH_RINGS", 8)
        monkeypatch.setattr(mesh_amount, "PATCH_MARGIN", 3)
    options = dict(faces=faces, weld=True, border="curve")
    run = core.MeshSmoother(noisy, edges, **options)
    fractions = list(run.steps(chunk=1))
    restoring = 1.0 - core.mesh.smooth.RESTORE_SHARE
    assert run.report.volume_offset > 0.0 and fractions == sorted(fractions)
    assert fractions.count(0.0) >= 5  # welding, surface, noise test, choice's preparation
    assert sum(0.0 < f < restoring for f in fractions) > run.report.iterations  # choice and smoothing
    assert fractions.count(restoring) >= 3  # the restore's rounds
    for stop in (1, 3, 6, fractions.index(restoring) + 1, len(fractions) - 1):
        run = core.MeshSmoother(noisy, edges, **options)
        steps = run.steps(chunk=1)
        for _ in range(stop):
            next(steps)
        steps.close()
        assert run.result is None and run.report is None and np.array_equal(noisy, before)


def test_fixed_and_zero_influence_stay_bit_for_bit_through_the_volume_restore(noisy_sphere):
    noisy, edges, faces = noisy_sphere
    fixed = np.zeros(len(noisy), bool)
    fixed[::7] = True
    influence = np.ones(len(noisy), np.float32)
    influence[3::11] = 0.0
    result, report = core.smooth_mesh(noisy, edges, faces=faces, fixed=fixed, influence=influence, return_report=True)
    assert report.volume_offset > 0.0
    still = fixed | (influence == 0.0)
    assert np.array_equal(result[still], noisy[still]) and not np.array_equal(result[~still], noisy[~still])


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(alpha="more"), "alpha must be 'auto' or a number"),
        (dict(iterations="lots"), "iterations must be 'auto' or a number"),
        (dict(alpha=1.5), "alpha"),
        (dict(iterations=-1), "iterations"),
        (dict(method="taubin"), "method"),
    ],
)
def test_bad_settings_are_refused_before_any_work(noisy_sphere, options, message):
    noisy, edges, _ = noisy_sphere
    with pytest.raises(ValueError, match=message):
        core.MeshSmoother(noisy, edges, **options)


def test_report_splits_the_run_into_choosing_iterations_and_finishing(noisy_sphere):
    """The Automatic Amount's run: its choice and its finishing rules take part of its time, the set numbers'
    run chooses nothing (only the welding check and the border rule go before its iterations)."""
    noisy, edges, faces = noisy_sphere
    _, automatic = core.smooth_mesh(noisy, edges, faces=faces, return_report=True)
    assert 0 < automatic.choosing_seconds and 0 < automatic.finishing_seconds
    assert automatic.choosing_seconds + automatic.finishing_seconds <= automatic.seconds
    _, given = core.smooth_mesh(noisy, edges, faces=faces, iterations=5, return_report=True)
    assert given.choosing_seconds + given.finishing_seconds <= given.seconds
    assert given.choosing_seconds < automatic.choosing_seconds
