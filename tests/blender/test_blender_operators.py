"""object.hc_smooth and mesh.hc_smooth on generated meshes, asserting on geometry."""

import re

import bpy
import numpy as np
import pytest
from blender_scene import (
    edges_of,
    faces_of,
    in_world,
    noisy_grid,
    noisy_sphere,
    positions_of,
    select_only,
    transformed,
)

import core

# Blender stores float properties in single precision: compare with the values the operator really got.
ALPHA, BETA = float(np.float32(0.1)), float(np.float32(0.6))


def bits(array):
    return np.ascontiguousarray(array).view(np.uint8)


def volume_change(before, after, mesh):
    return core.measure_change(before, after, faces=np.array(faces_of(mesh))).volume_change


def test_object_mode_equals_core_on_the_same_arrays(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth(auto_amount=False, alpha=0.25, beta=0.75, iterations=7) == {"FINISHED"}
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=0.25, beta=0.75, iterations=7)
    assert np.array_equal(positions_of(obj.data), expected)
    for mode, method in (("SEQUENTIAL", "HC"), ("SIMULTANEOUS", "LAPLACIAN_ORIGINAL")):
        start = positions_of(obj.data)
        bpy.ops.object.hc_smooth(auto_amount=False, method=method, mode=mode, alpha=0.25, beta=0.625, iterations=3)
        expected = core.smooth(
            start,
            edges_of(obj.data),
            method="hc" if method == "HC" else "original",
            mode=mode.lower(),
            alpha=0.25,
            beta=0.625,
            iterations=3,
        ).positions
        assert np.array_equal(positions_of(obj.data), expected)


def add_on_default(before, obj, **given):
    """What the add-on runs with nothing set but ``given``: core.smooth_mesh with the Automatic Amount,
    split vertices welded."""
    triangles = core.geometry.fan_triangles(np.array(faces_of(obj.data)))
    return core.smooth_mesh(
        before, edges_of(obj.data), faces=triangles, weld=True, border="free", return_report=True, **given
    )


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")  # alpha 0 for the chosen iterations, on purpose
def test_automatic_amount_is_the_default_and_keeps_the_volume(scene, capfd):
    """With nothing set, HC runs core's Automatic Amount (alpha 0) and gives the closed mesh its volume
    back; the report says what it chose. Off, alpha and iterations run as set."""
    obj = noisy_sphere()
    before = positions_of(obj.data)
    edges = edges_of(obj.data)
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    expected, report = add_on_default(before, obj)
    assert report.amount.noise_found and report.iterations > 1 and report.alpha == 0.0
    np.testing.assert_allclose(positions_of(obj.data), expected, rtol=0, atol=1e-6)
    assert abs(volume_change(before, positions_of(obj.data), obj.data)) < 1e-4
    said = capfd.readouterr().out
    assert (
        f"automatic amount: noise {report.amount.ratio:.2f}x edge length, {report.iterations} iterations, "
        f"alpha 0, beta {report.beta:.3g}" in said
    )
    assert "volume kept" in said
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=4) == {"FINISHED"}
    assert np.array_equal(positions_of(obj.data), core.hc_smooth(before, edges, alpha=ALPHA, beta=BETA, iterations=4))
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    assert bpy.ops.object.hc_smooth(method="LAPLACIAN", iterations=2) == {"FINISHED"}  # HC only
    assert np.array_equal(positions_of(obj.data), core.laplacian_smooth(before, edges, iterations=2))


@pytest.mark.parametrize(
    "given, numbers",
    [
        (dict(alpha=0.1, beta=0.6, iterations=10), (ALPHA, BETA, 10)),
        (dict(iterations=5), (ALPHA, BETA, 5)),
        (dict(alpha=0.25), (0.25, BETA, 10)),
    ],
)
def test_numbers_a_caller_sets_are_used_exactly(scene, capfd, given, numbers):
    """Alpha or Iterations set from Python: the Automatic Amount (on by default) does not run; every
    number runs as set (the others at their defaults), bit for bit what core.hc_smooth gives."""
    obj = noisy_sphere()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth(**given) == {"FINISHED"}
    alpha, beta, iterations = numbers
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=alpha, beta=beta, iterations=iterations)
    assert np.array_equal(positions_of(obj.data), expected)
    report = capfd.readouterr().out
    assert f": {iterations} iterations," in report and "automatic" not in report


def test_edit_mode_uses_the_iterations_set(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    assert bpy.ops.mesh.hc_smooth(iterations=5) == {"FINISHED"}
    bpy.ops.object.mode_set(mode="OBJECT")
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=5)
    assert np.array_equal(positions_of(obj.data), expected)


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")
def test_a_beta_set_is_kept_by_the_automatic_amount(scene, capfd):
    """A Beta the caller sets is used as set while the Automatic Amount chooses the iterations (unset, it
    may take gentler steps on light noise: core's tests show when)."""
    obj = noisy_sphere()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth(beta=0.7) == {"FINISHED"}
    expected, report = add_on_default(before, obj, beta=float(np.float32(0.7)))
    assert report.amount is not None and report.beta == float(np.float32(0.7))
    np.testing.assert_allclose(positions_of(obj.data), expected, rtol=0, atol=1e-6)
    assert f"{report.iterations} iterations, alpha 0, beta 0.7," in capfd.readouterr().out


def test_hc_keeps_volume_far_better_than_laplacian(scene, capfd):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    bpy.ops.object.hc_smooth(auto_amount=False, method="HC", iterations=30)
    hc = positions_of(obj.data)
    report = capfd.readouterr().out
    assert "HC on 'Sphere': 30 iterations" in report and "volume" in report
    obj.data.vertices.foreach_set("co", before.ravel())
    bpy.ops.object.hc_smooth(auto_amount=False, method="LAPLACIAN", iterations=30)
    laplacian = positions_of(obj.data)
    hc_change, lap_change = volume_change(before, hc, obj.data), volume_change(before, laplacian, obj.data)
    assert lap_change < -0.3 and abs(hc_change) < 0.05 and abs(hc_change) < 0.1 * abs(lap_change)
    # and it did smooth: the spread of the radii (the noise) dropped
    assert np.std(np.linalg.norm(hc, axis=1)) < 0.5 * np.std(np.linalg.norm(before, axis=1))


def test_vertex_group_is_fixed_and_inversion_smooths_only_the_group(scene):
    obj = noisy_sphere()
    group = obj.vertex_groups.new(name="Keep")
    members = np.flatnonzero(positions_of(obj.data)[:, 2] > 0.3)
    group.add(members.tolist(), 1.0, "REPLACE")
    before = positions_of(obj.data)
    bpy.ops.object.hc_smooth(auto_amount=False, vertex_group="Keep", iterations=5)
    after = positions_of(obj.data)
    assert np.array_equal(bits(after[members]), bits(before[members]))
    outside = np.setdiff1d(np.arange(len(before)), members)
    assert (np.linalg.norm(after[outside] - before[outside], axis=1) > 0).mean() > 0.9
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=5, fixed=members)
    assert np.array_equal(after, expected)

    obj.data.vertices.foreach_set("co", before.ravel())
    bpy.ops.object.hc_smooth(auto_amount=False, vertex_group="Keep", invert_vertex_group=True, iterations=5)
    after = positions_of(obj.data)
    assert np.array_equal(bits(after[outside]), bits(before[outside]))
    assert (np.linalg.norm(after[members] - before[members], axis=1) > 0).mean() > 0.9


def test_pin_boundary_keeps_open_edges_in_place(scene):
    obj = noisy_grid()
    before = positions_of(obj.data)
    xy = np.abs(before[:, :2])
    boundary = np.isclose(xy, 1.0, atol=1e-5).any(axis=1)
    assert 0 < boundary.sum() < len(before)
    bpy.ops.object.hc_smooth(auto_amount=False, pin_boundary=True, iterations=5)
    after = positions_of(obj.data)
    assert np.array_equal(bits(after[boundary]), bits(before[boundary]))
    assert np.all(np.linalg.norm(after[~boundary] - before[~boundary], axis=1) > 0)


def test_keep_outline_runs_cores_curve_rule_and_keeps_the_outline(scene, capfd):
    """Keep Outline: open boundaries smoothed as curves (core border="curve"), so the grid's outline stays
    where the paper's rule pulls it in; Pin Boundary wins when both are on. The panel's count includes the
    corners the rule holds."""
    obj = noisy_grid()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth(keep_outline=True, iterations=20) == {"FINISHED"}
    triangles = core.geometry.fan_triangles(np.array(faces_of(obj.data)))
    expected = core.smooth_mesh(
        before, edges_of(obj.data), faces=triangles, weld=True, border="curve", alpha=ALPHA, beta=BETA, iterations=20
    )
    assert np.array_equal(positions_of(obj.data), expected)
    curve_box = np.ptp(positions_of(obj.data)[:, :2], axis=0)
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    bpy.ops.object.hc_smooth(iterations=20)
    free_box = np.ptp(positions_of(obj.data)[:, :2], axis=0)
    start_box = np.ptp(before[:, :2], axis=0)
    assert np.all(free_box < start_box - 0.06)  # the paper's rule pulls the outline in by 3.5 %
    assert np.abs(curve_box - start_box).max() < 0.5 * np.abs(free_box - start_box).max()
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    bpy.ops.object.hc_smooth(keep_outline=True, pin_boundary=True, iterations=5)
    boundary = np.isclose(np.abs(before[:, :2]), 1.0, atol=1e-5).any(axis=1)
    assert np.array_equal(bits(positions_of(obj.data)[boundary]), bits(before[boundary]))


def test_shape_keys_smooth_the_active_key_without_desyncing_the_basis(scene):
    obj = noisy_sphere()
    basis = obj.shape_key_add(name="Basis", from_mix=False)
    key = obj.shape_key_add(name="Scan", from_mix=False)
    obj.active_shape_key_index = 1
    mesh_before = positions_of(obj.data)
    bpy.ops.object.hc_smooth(auto_amount=False, iterations=4)
    key_after = np.array([v.co[:] for v in key.data], dtype=np.float32)
    basis_after = np.array([v.co[:] for v in basis.data], dtype=np.float32)
    expected = core.hc_smooth(mesh_before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=4)
    assert np.array_equal(key_after, expected)
    assert np.array_equal(basis_after, mesh_before) and np.array_equal(positions_of(obj.data), mesh_before)

    obj.active_shape_key_index = 0  # smoothing the basis moves the mesh with it
    bpy.ops.object.hc_smooth(auto_amount=False, iterations=4)
    basis_after = np.array([v.co[:] for v in basis.data], dtype=np.float32)
    assert np.array_equal(basis_after, expected) and np.array_equal(positions_of(obj.data), expected)


def test_output_to_a_new_shape_key_leaves_the_mesh(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    bpy.ops.object.hc_smooth(auto_amount=False, output="SHAPE_KEY", iterations=4)
    assert np.array_equal(bits(positions_of(obj.data)), bits(before))
    keys = obj.data.shape_keys.key_blocks
    assert [k.name for k in keys] == ["Basis", "HC Smooth"]
    result = np.array([v.co[:] for v in keys["HC Smooth"].data], dtype=np.float32)
    assert np.array_equal(result, core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=4))


def test_a_mesh_shared_by_several_objects_is_smoothed_once(scene):
    obj = noisy_sphere()
    twin = bpy.data.objects.new("Twin", obj.data)
    scene.collection.objects.link(twin)
    select_only(obj, twin)
    before = positions_of(obj.data)
    bpy.ops.object.hc_smooth(auto_amount=False, iterations=3)
    once = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=3)
    assert np.array_equal(positions_of(obj.data), once)


def test_several_objects_each_smoothed(scene):
    a, b = noisy_sphere("A", seed=1), noisy_sphere("B", seed=2)
    select_only(a, b)
    before = {o.name: positions_of(o.data) for o in (a, b)}
    bpy.ops.object.hc_smooth(auto_amount=False, iterations=3)
    for o in (a, b):
        expected = core.hc_smooth(before[o.name], edges_of(o.data), alpha=ALPHA, beta=BETA, iterations=3)
        assert np.array_equal(positions_of(o.data), expected)


def test_edit_mode_moves_only_selected_visible_vertices(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    n = len(before)
    selected = before[:, 0] > -0.2
    hidden = np.zeros(n, dtype=bool)
    hidden[np.flatnonzero(selected)[:10]] = True
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    bpy.ops.object.mode_set(mode="OBJECT")
    obj.data.vertices.foreach_set("select", selected)
    obj.data.vertices.foreach_set("hide", hidden)
    bpy.ops.object.mode_set(mode="EDIT")
    assert bpy.ops.mesh.hc_smooth(auto_amount=False, iterations=5) == {"FINISHED"}
    assert bpy.context.mode == "EDIT_MESH"
    bpy.ops.object.mode_set(mode="OBJECT")
    after = positions_of(obj.data)
    fixed = ~selected | hidden
    assert np.array_equal(bits(after[fixed]), bits(before[fixed]))
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=5, fixed=fixed)
    assert np.array_equal(after, expected)


def test_edit_mode_with_nothing_selected_says_so_and_stays_in_edit_mode(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    with pytest.raises(RuntimeError, match="Select some visible vertices"):
        bpy.ops.mesh.hc_smooth()
    assert bpy.context.mode == "EDIT_MESH"
    bpy.ops.object.mode_set(mode="OBJECT")
    assert np.array_equal(bits(positions_of(obj.data)), bits(before))


def test_invoke_in_background_runs_execute(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth("INVOKE_DEFAULT", auto_amount=False, iterations=2) == {"FINISHED"}
    assert np.array_equal(
        positions_of(obj.data), core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=2)
    )


def test_outside_the_convergence_region_warns(scene, capfd):
    noisy_sphere()
    assert bpy.ops.object.hc_smooth(auto_amount=False, alpha=0.1, beta=0.3, iterations=2) == {"FINISHED"}
    assert "Theorem 5.2" in capfd.readouterr().out


def test_the_deviation_limit_set_is_kept(scene, capfd):
    """Deviation Limit set: no vertex ends farther than it from where it started; with numbers set too,
    the core's HC with that limit, bit for bit."""
    obj = noisy_sphere()
    before = positions_of(obj.data)
    limit = float(np.float32(0.004))
    assert bpy.ops.object.hc_smooth(iterations=10, max_deviation=0.004) == {"FINISHED"}
    after = positions_of(obj.data)
    expected = core.smooth(
        before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=10, max_deviation=limit
    ).positions
    assert np.array_equal(after, expected)
    assert np.linalg.norm(after.astype(float) - before, axis=1).max() <= limit + 1e-7
    free = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=10)
    assert np.linalg.norm(free.astype(float) - before, axis=1).max() > 2 * limit  # the limit binds


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")
def test_the_automatic_amount_keeps_to_a_multiple_of_its_noise(scene, capfd):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    report = capfd.readouterr().out
    limit = float(re.search(r"moves at most ([0-9.e-]+)", report).group(1))
    amount = core.choose_amount(before, edges_of(obj.data))
    assert limit == pytest.approx(core.mesh.smooth.DEVIATION_IN_NOISE * amount.sigma, rel=1e-2)
    assert np.linalg.norm(positions_of(obj.data).astype(float) - before, axis=1).max() <= limit * 1.001 + 1e-7


# --- world space: a Deviation Limit and a report in scene units are measured on the object as it stands -----

TRANSFORMS = {
    "scaled x10": dict(scale=(10.0, 10.0, 10.0)),
    "scaled (1, 1, 10)": dict(scale=(1.0, 1.0, 10.0)),
    "scaled (1, 1, 10), rotated": dict(scale=(1.0, 1.0, 10.0), rotation_euler=(0.4, -0.3, 1.1)),
    "mirrored, scaled (-2, 0.5, 3), rotated": dict(scale=(-2.0, 0.5, 3.0), rotation_euler=(1.2, 0.1, -0.7)),
}


def world_moves(obj, before):
    return np.linalg.norm(in_world(obj, positions_of(obj.data)) - in_world(obj, before), axis=1)


def rounding(obj, positions):
    """How far single-precision object-space coordinates can put a world-space length off."""
    return 4 * float(np.finfo(np.float32).eps) * float(np.abs(in_world(obj, positions)).max())


def reported(text, words):
    """The number a report gives after ``words`` (its scene-unit value in parentheses, if any)."""
    return float(re.search(re.escape(words) + r" (?:[-+0-9.]+% \()?([-+0-9.e]+)", text).group(1))


@pytest.mark.parametrize("transform", TRANSFORMS)
def test_the_deviation_limit_and_the_report_are_in_world_space(scene, capfd, transform):
    """A Deviation Limit of 0.01 on a scaled (rotated, mirrored) object: no vertex moves more than 0.01 in the
    world, and the report's largest move is the world's; the same numbers as core on the world-space shape."""
    obj = transformed(noisy_sphere(), **TRANSFORMS[transform])
    before = positions_of(obj.data)
    limit = float(np.float32(0.01))
    capfd.readouterr()
    assert bpy.ops.object.hc_smooth(iterations=10, max_deviation=0.01) == {"FINISHED"}
    moves = world_moves(obj, before)
    assert moves.max() <= limit + rounding(obj, before) and moves.max() > 0.99 * limit  # kept, and binding
    assert reported(capfd.readouterr().out, "largest move") == pytest.approx(moves.max(), rel=2e-3)
    # Linear steps: without the limit the run is the object-space one (to rounding).
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    assert bpy.ops.object.hc_smooth(iterations=10) == {"FINISHED"}
    free = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=10)
    np.testing.assert_allclose(positions_of(obj.data), free, rtol=0, atol=1e-5 * np.abs(before).max())


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")
@pytest.mark.parametrize("transform", ["scaled (1, 1, 10), rotated", "mirrored, scaled (-2, 0.5, 3), rotated"])
def test_the_automatic_amounts_limit_is_in_world_space(scene, capfd, transform):
    obj = transformed(noisy_sphere(subdivisions=4, sigma=0.03), **TRANSFORMS[transform])  # dense: smoothed, not held
    before = positions_of(obj.data)
    capfd.readouterr()
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    said = capfd.readouterr().out
    limit = reported(said, "moves at most")
    moves = world_moves(obj, before)
    assert moves.max() <= limit * 1.001 + rounding(obj, before)
    assert reported(said, "largest move") == pytest.approx(moves.max(), rel=2e-3)


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")
def test_a_uniform_scale_scales_the_automatic_amount_with_it(scene, capfd):
    """Object x8 (mirrored too): the Automatic Amount runs on the world-space shape, which is the unscaled one
    times 8: the same vertices in object space, and a limit 8 times the unscaled object's."""
    plain = noisy_sphere("Plain")
    big = transformed(noisy_sphere("Big"), scale=(-8.0, 8.0, 8.0))
    select_only(plain)
    capfd.readouterr()
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    plain_limit = reported(capfd.readouterr().out, "moves at most")
    select_only(big)
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    assert reported(capfd.readouterr().out, "moves at most") == pytest.approx(8 * plain_limit, rel=2e-3)
    np.testing.assert_allclose(positions_of(big.data), positions_of(plain.data), rtol=0, atol=1e-6)


def test_an_object_scaled_to_nothing_is_refused(scene):
    obj = transformed(noisy_sphere(), scale=(1.0, 0.0, 1.0))
    before = positions_of(obj.data)
    with pytest.raises(RuntimeError, match="Object 'Sphere': the object's scale is zero, or nearly, along an axis"):
        bpy.ops.object.hc_smooth(max_deviation=0.01)
    assert np.array_equal(bits(positions_of(obj.data)), bits(before))
