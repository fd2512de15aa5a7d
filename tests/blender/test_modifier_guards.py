"""The HC Smooth modifier cannot write garbage, and it keeps core's Deviation Limit.

Guards: whoever sets the inputs (the operator, the add-on's set_input, a script writing the modifier's ID
properties or RNA, NaN included), they are clamped to their ranges inside the node tree; HC with Beta below
0.5 beyond nodes.hc_group.SAFE_HC_STEPS iterations, a NaN input and a result that is not finite or has blown
up pass the mesh through unchanged, with a line in the modifier's Warnings panel (modifier.node_warnings,
filled by an evaluation also without a window). Applying such a modifier leaves the mesh as it was.

Deviation Limit: applying the modifier gives core.smooth(..., max_deviation=r) for every method, within the
tolerance of test_modifier.py.
"""

import math

import bpy
import numpy as np
import pytest
from blender_scene import edges_of, make_mesh_object, noisy_grid, noisy_sphere, positions_of, select_only
from test_modifier import (
    ALPHA,
    BETA,
    CORE_METHOD,
    ITERATIONS,
    TOLERANCE,
    add_modifier,
    diagonal,
    evaluated_positions,
    f32,
    module,
    painted,
)

import core


def messages(modifier, kind=None):
    """The lines of the modifier's Warnings panel after an evaluation: [(type, message)]."""
    evaluated_positions(modifier.id_data)
    return [(w.type, w.message) for w in modifier.node_warnings if kind is None or w.type == kind]


def refused(modifier, words):
    """Whether an Error line with ``words`` says the mesh is passed through."""
    return any(words in message and "passed through unchanged" in message for _, message in messages(modifier, "ERROR"))


def write_raw(modifier, name, value):
    """What a script writes without the add-on's helpers: an ID property in 4.x, the RNA value in Blender 5."""
    identifier = module("nodes.inputs").input_identifier(modifier.node_group, name)
    if hasattr(modifier, "properties") and hasattr(modifier.properties, "inputs"):
        getattr(modifier.properties.inputs, identifier).value = value
    else:
        modifier[identifier] = value
    modifier.id_data.update_tag()


def same_bits(a, b):
    return np.array_equal(np.asarray(a).view(np.uint32), np.asarray(b).view(np.uint32))


# --- outside the convergence region ----------------------------------------------------------------------


def test_hc_with_beta_zero_is_refused_and_applying_keeps_the_mesh(scene):
    # The reproducer: Alpha 0, Beta 0 (inside the sliders' range), 300 iterations gave coordinates of 3.9e22.
    obj = noisy_sphere()
    before = positions_of(obj.data)
    modifier = add_modifier(obj, method="HC", alpha=0.0, beta=0.0, iterations=300)
    assert same_bits(evaluated_positions(obj), before)
    assert refused(modifier, "HC with Beta below 0.5 can blow up")
    assert bpy.ops.object.modifier_apply(modifier=modifier.name) == {"FINISHED"}
    assert same_bits(positions_of(obj.data), before)
    # Without the guard the same run blows up: core refuses it too.
    with pytest.warns(core.ConvergenceWarning), pytest.raises(core.DivergenceError):
        core.smooth(before, edges_of(obj.data), alpha=0.0, beta=0.0, iterations=300)


def checkerboard(name="Checker", size=20):
    """A grid whose vertices alternate between heights +-0.05 like a checkerboard: the pattern HC with Beta 0
    amplifies most (T q = -q inside, so each iteration multiplies it by up to 3)."""
    obj = noisy_grid(name, size=size, sigma=0.0)
    positions = positions_of(obj.data)
    cell = np.rint((positions[:, :2] + 1.0) * size / 2.0).astype(int)
    positions[:, 2] = np.where(cell.sum(axis=1) % 2, 0.05, -0.05)
    obj.data.vertices.foreach_set("co", positions.ravel())
    obj.data.update()
    return obj


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")  # outside the region on purpose
def test_hc_below_half_beta_runs_its_safe_iterations(scene):
    hc_group = module("nodes.hc_group")
    steps = hc_group.SAFE_HC_STEPS
    obj = checkerboard()
    before = positions_of(obj.data)
    modifier = add_modifier(obj, method="HC", alpha=0.0, beta=0.0, iterations=steps)
    got = evaluated_positions(obj)
    want = core.smooth(before, edges_of(obj.data), alpha=0.0, beta=0.0, iterations=steps).positions
    assert np.abs(got - want).max() <= TOLERANCE * diagonal(before)
    assert np.ptp(got[:, 2]) > 4 * np.ptp(before[:, 2])  # it grew, and still ran
    assert diagonal(np.concatenate([got, before])) <= 3**steps * diagonal(before)
    assert not messages(modifier, "ERROR")
    assert any("proven to converge only" in message for _, message in messages(modifier, "INFO"))
    module("nodes.inputs").set_input(modifier, "Iterations", steps + 1)
    assert same_bits(evaluated_positions(obj), before) and refused(modifier, "Beta below 0.5")


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")  # alpha 0 on purpose
def test_alpha_zero_with_beta_above_half_runs_with_a_note(scene):
    # What the Automatic Amount runs: alpha 0 is outside the proven region, but cannot blow up with beta >= 0.5.
    obj = noisy_sphere()
    modifier = add_modifier(obj, method="HC", alpha=0.0, beta=0.6, iterations=50)
    want = core.smooth(positions_of(obj.data), edges_of(obj.data), alpha=0.0, beta=f32(0.6), iterations=50)
    assert np.abs(evaluated_positions(obj) - want.positions).max() <= TOLERANCE * diagonal(want.positions)
    assert not messages(modifier, "ERROR")
    assert [kind for kind, _ in messages(modifier)] == ["INFO"]
    module("nodes.inputs").set_input(modifier, "Alpha", 0.1)
    assert messages(modifier) == []


def test_the_blow_up_test_catches_what_gets_past_the_inputs(scene, monkeypatch):
    # With more steps allowed below Beta 0.5 the run grows past 10 times the box, then to inf and NaN: the
    # result's test passes the mesh through at each stage.
    hc_group = module("nodes.hc_group")
    monkeypatch.setattr(hc_group, "SAFE_HC_STEPS", 10_000)
    obj = checkerboard()
    before = positions_of(obj.data)
    modifier = add_modifier(obj, method="HC", alpha=0.0, beta=0.0, iterations=10)
    assert not any("Beta below 0.5" in message for _, message in messages(modifier))
    inputs = module("nodes.inputs")
    edges = edges_of(obj.data)
    for iterations, what in ((10, "the bounding box grew"), (300, "blew up after"), (1000, "infinite or NaN")):
        inputs.set_input(modifier, "Iterations", iterations)
        assert same_bits(evaluated_positions(obj), before), iterations
        assert refused(modifier, "Smoothing blew up"), iterations
        with pytest.warns(core.ConvergenceWarning), pytest.raises(core.DivergenceError, match=what):
            core.smooth(before, edges, alpha=0.0, beta=0.0, iterations=iterations)
    assert bpy.ops.object.modifier_apply(modifier=modifier.name) == {"FINISHED"}
    assert same_bits(positions_of(obj.data), before)


def test_an_input_that_overflows_is_passed_through(scene):
    # A vertex near float32's largest value: its neighbours' averages overflow to inf.
    obj = noisy_grid("Huge")
    before = positions_of(obj.data)
    before[40] = (3e38, 3e38, 0.0)
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    modifier = add_modifier(obj, method="LAPLACIAN")
    assert same_bits(evaluated_positions(obj), positions_of(obj.data))
    assert refused(modifier, "Smoothing blew up")


# --- inputs clamped whoever sets them ----------------------------------------------------------------------


def result_with(obj, **values):
    """The evaluated positions of a fresh modifier with the add-on's own settings ``values``."""
    modifier = add_modifier(obj, **values)
    got = evaluated_positions(obj)
    obj.modifiers.remove(modifier)
    return got


@pytest.mark.parametrize(
    ("method", "name", "value", "nearest"),
    [
        ("HC", "Beta", 7.0, 1.0),
        ("HC", "Alpha", 3.0, 1.0),
        ("HC", "Alpha", -0.5, 0.0),
        ("LAPLACIAN_ORIGINAL", "Alpha", -1.0, 0.0),
        ("LAPLACIAN_CENTRAL", "Alpha", 2.0, 1.0),
    ],
)
def test_values_out_of_range_are_clamped(scene, method, name, value, nearest):
    obj = noisy_sphere()
    want = result_with(obj, method=method, **{name.lower(): nearest})
    inputs = module("nodes.inputs")
    for write in (inputs.set_input, write_raw):
        modifier = add_modifier(obj, method=method)
        write(modifier, name, value)
        assert same_bits(evaluated_positions(obj), want), (write, name, value)
        assert inputs.get_input(modifier, name) == pytest.approx(value)  # stored as written: the tree clamps it
        assert any(message.startswith(f"{name} is outside 0 to 1") for _, message in messages(modifier, "INFO"))
        assert not messages(modifier, "ERROR")
        obj.modifiers.remove(modifier)


def test_beta_below_range_is_zero_and_then_refused(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    modifier = add_modifier(obj, method="HC")
    write_raw(modifier, "Beta", -3.0)  # gave NaN
    assert same_bits(evaluated_positions(obj), before) and refused(modifier, "Beta below 0.5")


@pytest.mark.parametrize("name", ["Alpha", "Beta", "Deviation Limit"])
def test_not_a_number_passes_the_mesh_through(scene, name):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    modifier = add_modifier(obj, method="LAPLACIAN_ORIGINAL")
    inputs = module("nodes.inputs")
    for write in (inputs.set_input, write_raw):
        write(modifier, name, math.nan)
        assert math.isnan(inputs.get_input(modifier, name))  # stored as written: the tree refuses it
        assert same_bits(evaluated_positions(obj), before), write
        assert refused(modifier, f"{name} is not a number"), write
        write(modifier, name, 0.0)
        assert not same_bits(evaluated_positions(obj), before)


def test_iterations_have_a_hard_maximum(scene):
    spec = module("settings_spec")
    most = spec.MODIFIER_MAX_ITERATIONS
    assert spec.MODIFIER_ITERATIONS.soft_max < most and str(most) in spec.MODIFIER_ITERATIONS.description
    assert "cannot interrupt" in spec.MODIFIER_ITERATIONS.description
    obj = noisy_sphere(subdivisions=1)
    want = result_with(obj, method="LAPLACIAN_ORIGINAL", alpha=0.01, iterations=most)
    select_only(obj)
    # The operator's property has the same hard maximum: a larger number is clamped by Blender.
    assert bpy.ops.object.hc_smooth_modifier_add(method="LAPLACIAN_ORIGINAL", alpha=0.01, iterations=10 * most)
    modifier = obj.modifiers[-1]
    inputs = module("nodes.inputs")
    assert inputs.get_input(modifier, "Iterations") == most
    assert same_bits(evaluated_positions(obj), want)
    group = modifier.node_group
    socket = next(
        item for item in group.interface.items_tree if item.item_type == "SOCKET" and item.name == "Iterations"
    )
    assert (socket.min_value, socket.max_value) == (0, most)
    assert "cannot interrupt" in socket.description
    for write in (inputs.set_input, write_raw):
        write(modifier, "Iterations", 2**31 - 1)
        assert same_bits(evaluated_positions(obj), want), write
        assert inputs.get_input(modifier, "Iterations") > most
        assert any(message.startswith("Iterations is outside") for _, message in messages(modifier, "INFO"))
        write(modifier, "Iterations", -5)
        assert same_bits(evaluated_positions(obj), positions_of(obj.data)), write


def test_influence_weights_out_of_range_or_nan_are_clipped(scene):
    # The Influence field can read any float attribute, NaN included: below 0 and NaN stay, above 1 is the full step.
    obj = noisy_sphere()
    n = len(obj.data.vertices)
    weights = np.resize(np.array([-2.0, np.nan, 0.5, 1.0, 7.0], dtype=np.float32), n)
    attribute = obj.data.attributes.new("Odd", "FLOAT", "POINT")
    attribute.data.foreach_set("value", weights)
    modifier = add_modifier(obj, method="HC")
    module("nodes.inputs").set_input_attribute(modifier, "Influence", "Odd")
    clipped = np.clip(np.nan_to_num(weights, nan=0.0), 0.0, 1.0)
    want = core.smooth(
        positions_of(obj.data),
        edges_of(obj.data),
        alpha=f32(ALPHA),
        beta=f32(BETA),
        iterations=ITERATIONS,
        influence=clipped,
    ).positions
    got = evaluated_positions(obj)
    assert np.isfinite(got).all() and np.abs(got - want).max() <= TOLERANCE * diagonal(want)
    still = clipped == 0.0
    assert same_bits(got[still], positions_of(obj.data)[still])


# --- the Deviation Limit -----------------------------------------------------------------------------------


@pytest.mark.parametrize("method", CORE_METHOD)
def test_applying_with_a_deviation_limit_equals_core(scene, method):
    obj = noisy_grid("Patch", size=16)
    weights = painted(obj)
    before = positions_of(obj.data)
    edges = edges_of(obj.data)
    options = dict(alpha=f32(ALPHA), beta=f32(BETA), iterations=ITERATIONS, method=CORE_METHOD[method])
    free = core.smooth(before, edges, **options).positions
    moves = np.linalg.norm(free - before, axis=1)
    limit = f32(0.4 * float(moves.max()))
    want = core.smooth(before, edges, max_deviation=limit, **options).positions
    assert (moves > limit).sum() > len(moves) // 20  # the limit binds on a part of the mesh
    modifier = add_modifier(obj, method=method, max_deviation=limit)
    assert module("nodes.inputs").get_input(modifier, "Deviation Limit") == pytest.approx(limit)
    assert bpy.ops.object.modifier_apply(modifier=modifier.name) == {"FINISHED"}
    applied = positions_of(obj.data)
    assert np.abs(applied - want).max() <= TOLERANCE * diagonal(before)
    assert np.linalg.norm(applied - before, axis=1).max() <= limit * (1 + 1e-5)
    # With painted influence, inverted (the limit comes after the influence, as in core).
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    add_modifier(obj, method=method, max_deviation=limit, influence_group="Paint", invert_influence_group=True)
    influence = np.clip(np.float32(1.0) - weights, 0.0, 1.0)
    want = core.smooth(before, edges, max_deviation=limit, influence=influence, **options).positions
    assert np.abs(evaluated_positions(obj) - want).max() <= TOLERANCE * diagonal(before)


def test_deviation_limit_with_fixed_vertices_and_zero_as_no_limit(scene):
    obj = noisy_sphere()
    fixed = np.zeros(len(obj.data.vertices), dtype=bool)
    fixed[::5] = True
    obj.vertex_groups.new(name="Keep").add(np.flatnonzero(fixed).tolist(), 1.0, "REPLACE")
    before = positions_of(obj.data)
    modifier = add_modifier(obj, method="HC", vertex_group="Keep", max_deviation=0.004)
    options = dict(alpha=f32(ALPHA), beta=f32(BETA), iterations=ITERATIONS, fixed=fixed)
    want = core.smooth(before, edges_of(obj.data), max_deviation=f32(0.004), **options).positions
    got = evaluated_positions(obj)
    assert np.abs(got - want).max() <= TOLERANCE * diagonal(before) and same_bits(got[fixed], before[fixed])
    inputs = module("nodes.inputs")
    inputs.set_input(modifier, "Deviation Limit", 0.0)
    free = evaluated_positions(obj)
    inputs.set_input(modifier, "Deviation Limit", -1.0)  # below the range: no limit, and said so
    assert same_bits(evaluated_positions(obj), free)
    assert any(message.startswith("Deviation Limit is below 0") for _, message in messages(modifier, "INFO"))
    want = core.smooth(before, edges_of(obj.data), **options).positions
    assert np.abs(free - want).max() <= TOLERANCE * diagonal(before)


def test_a_big_limit_changes_no_bit_of_hc(scene):
    obj = noisy_sphere()
    modifier = add_modifier(obj, method="HC")
    free = evaluated_positions(obj)
    module("nodes.inputs").set_input(modifier, "Deviation Limit", 1e6)
    assert same_bits(evaluated_positions(obj), free)


def test_an_empty_mesh_and_a_single_point_pass(scene):
    for name, positions in (("Empty", []), ("Point", [(1.0, 2.0, 3.0)]), ("Pair", [(0, 0, 0), (0, 0, 0)])):
        obj = make_mesh_object(name, positions, edges=[(0, 1)] if len(positions) == 2 else ())
        modifier = add_modifier(obj, method="HC", max_deviation=0.1)
        assert same_bits(evaluated_positions(obj), positions_of(obj.data)), name
        assert not messages(modifier, "ERROR"), name
