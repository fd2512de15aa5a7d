"""The HC Smooth modifier (a Geometry Nodes group built by nodes/hc_group.py), through the evaluated depsgraph.

Its result must equal core's for every method on every kind of mesh, within single-precision rounding
(1e-5 of the bounding-box diagonal after 10 iterations), with a painted influence as core's influence=;
fixed vertices and those of influence 0 must not move at all. Applying it must give what object.hc_smooth
gives, and a file saved with it must evaluate the same without the add-on.
"""

import importlib

import bpy
import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.csgraph
from blender_scene import (
    ADDON,
    edges_of,
    in_world,
    noisy_grid,
    noisy_sphere,
    positions_of,
    select_only,
    transformed,
)
from test_ui import RecordingLayout, redo_panel

import core

ALPHA, BETA = 0.25, 0.7  # away from the defaults, so a default left in place would show
ITERATIONS = 10
TOLERANCE = 1e-5  # of the bounding-box diagonal: single-precision rounding after 10 iterations
CORE_METHOD = {"HC": "hc", "LAPLACIAN": "plain", "LAPLACIAN_CENTRAL": "central", "LAPLACIAN_ORIGINAL": "original"}
INPUT_NAMES = (
    "Method",
    "Alpha",
    "Beta",
    "Iterations",
    "Deviation Limit",
    "Fixed Group",
    "Invert Fixed Group",
    "Pin Boundary",
    "Influence",
    "Invert Influence",
    "Deviation Map",
)
# Painted weights: 0 (stays), 1 (the full step) and shares between that are not binary fractions.
INFLUENCE_LEVELS = (0.0, 0.3, 0.55, 0.8, 1.0)


def manual(**settings):
    """Mesh-operator settings that the modifier can hold: no Automatic Amount where the operators have it."""
    if "auto_amount" in bpy.ops.object.hc_smooth.get_rna_type().properties:
        settings["auto_amount"] = False
    return settings


def module(name):
    return importlib.import_module(f"{ADDON}.{name}")


def f32(value):
    """A float as the modifier holds it (single precision), for core to run the same numbers."""
    return float(np.float32(value))


def evaluated_positions(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    mesh = obj.evaluated_get(depsgraph).data
    buffer = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.attributes["position"].data.foreach_get("vector", buffer)
    return buffer.reshape(-1, 3)


def diagonal(positions):
    return float(np.linalg.norm(positions.max(axis=0) - positions.min(axis=0)))


def boundary_mask(mesh):
    """Vertices on an edge of exactly one face, counted here from the faces' edge keys."""
    uses = {}
    for polygon in mesh.polygons:
        for key in polygon.edge_keys:
            uses[key] = uses.get(key, 0) + 1
    mask = np.zeros(len(mesh.vertices), dtype=bool)
    for (a, b), count in uses.items():
        if count == 1:
            mask[[a, b]] = True
    return mask


def painted(obj, name="Paint", seed=4):
    """A vertex group of INFLUENCE_LEVELS weights, some vertices left out of it (weight 0); returns the
    weights as Blender stores them (float32), as core's influence= takes them."""
    rng = np.random.default_rng(seed)
    n = len(obj.data.vertices)
    weights = rng.choice(INFLUENCE_LEVELS, size=n).astype(np.float32)
    left_out = rng.random(n) < 0.15
    group = obj.vertex_groups.new(name=name)
    for level in INFLUENCE_LEVELS:
        group.add(np.flatnonzero((weights == np.float32(level)) & ~left_out).tolist(), level, "REPLACE")
    weights[left_out] = 0.0
    assert all((weights == np.float32(level)).any() for level in INFLUENCE_LEVELS)
    return weights


def inverted(weights):
    """The influence of an inverted group, as the operators take it (float32, clipped to [0, 1])."""
    return np.clip(np.float32(1.0) - weights, 0.0, 1.0)


def add_modifier(obj, **settings):
    select_only(obj)
    settings = dict(dict(alpha=ALPHA, beta=BETA, iterations=ITERATIONS), **settings)
    assert bpy.ops.object.hc_smooth_modifier_add(**settings) == {"FINISHED"}
    return obj.modifiers[-1]


def expected(obj, method, fixed=None, influence=None, **core_options):
    options = dict(alpha=f32(ALPHA), beta=f32(BETA), iterations=ITERATIONS)
    options.update(core_options)
    return core.smooth(
        positions_of(obj.data),
        edges_of(obj.data),
        method=CORE_METHOD[method],
        fixed=fixed,
        influence=influence,
        **options,
    ).positions


def check_equals_core(obj, method, fixed=None, influence=None, **settings):
    """The modifier with ``settings`` equals core with ``fixed`` and ``influence``; fixed vertices and those of
    influence 0 stay bit for bit. Returns the largest difference as a fraction of the diagonal."""
    before = positions_of(obj.data)
    add_modifier(obj, method=method, **settings)
    got, want = evaluated_positions(obj), expected(obj, method, fixed, influence=influence)
    error = float(np.abs(got - want).max()) / diagonal(before)
    assert error <= TOLERANCE, (method, error)
    assert np.abs(got - before).max() > 100 * TOLERANCE * diagonal(before)  # it did smooth
    if fixed is not None:
        assert np.array_equal(got[fixed].view(np.uint32), before[fixed].view(np.uint32))
    if influence is not None:
        still = influence == 0.0
        assert still.any() and np.array_equal(got[still].view(np.uint32), before[still].view(np.uint32))
        # The weights matter here: core without them is far from the modifier's result.
        unweighted = expected(obj, method, fixed)
        assert np.abs(got - unweighted).max() > 100 * TOLERANCE * diagonal(before)
    assert np.array_equal(positions_of(obj.data), before)  # a modifier never changes the mesh itself
    return error


def noisy(obj, sigma, seed=3):
    positions = positions_of(obj.data)
    positions += np.random.default_rng(seed).normal(scale=sigma, size=positions.shape).astype(np.float32)
    obj.data.vertices.foreach_set("co", positions.ravel())
    obj.data.update()
    return obj


def ngon_cylinder():
    """Quads around, one 16-gon at each end: closed, with n-gons."""
    bpy.ops.mesh.primitive_cylinder_add(vertices=16, depth=2.0, end_fill_type="NGON")
    obj = bpy.context.active_object
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.subdivide(number_cuts=3)  # more rings and inner vertices; the caps stay n-gons
    bpy.ops.object.mode_set(mode="OBJECT")
    assert max(len(polygon.vertices) for polygon in obj.data.polygons) >= 16
    return noisy(obj, 0.03)


def parts_and_loose():
    """A closed sphere, an open quad patch, a loose edge chain and three loose vertices in one mesh."""
    sphere = noisy_sphere("A", subdivisions=2)
    grid = noisy_grid("B", size=8)
    select_only(sphere, grid)
    bpy.ops.object.join()
    obj = bpy.context.active_object
    mesh = obj.data
    n = len(mesh.vertices)
    chain = np.array([[3.0, 0.0, 0.0], [3.2, 0.1, 0.0], [3.4, -0.1, 0.05], [3.6, 0.0, 0.0]], np.float32)
    loose = np.array([[-3.0, 0.0, 0.0], [0.0, -3.0, 0.0], [0.0, 0.0, 3.0]], np.float32)
    mesh.vertices.add(len(chain) + len(loose))
    mesh.vertices.foreach_set("co", np.concatenate([positions_of(mesh)[:n], chain, loose]).ravel())
    mesh.edges.add(len(chain) - 1)
    for edge, pair in zip(mesh.edges[-3:], ((n, n + 1), (n + 1, n + 2), (n + 2, n + 3))):
        edge.vertices = pair
    mesh.update()
    return obj, np.arange(n + len(chain), n + len(chain) + len(loose))


MESHES = {
    "closed triangles": lambda: noisy_sphere(),
    "open quads": lambda: noisy_grid(),
    "n-gons": ngon_cylinder,
}


# --- exactness -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", CORE_METHOD)
@pytest.mark.parametrize("shape", MESHES)
def test_modifier_equals_core(scene, shape, method):
    check_equals_core(MESHES[shape](), method)


@pytest.mark.parametrize("method", CORE_METHOD)
def test_parts_loose_edges_and_loose_vertices(scene, method):
    obj, loose = parts_and_loose()
    before = positions_of(obj.data)
    check_equals_core(obj, method)
    got = evaluated_positions(obj)
    assert np.array_equal(got[loose], before[loose])  # no neighbours: fixed, as in core
    chain = loose - 4
    assert np.abs(got[chain[1:3]] - before[chain[1:3]]).max() > 0  # a loose edge still joins neighbours


@pytest.mark.parametrize("method", CORE_METHOD)
def test_fixed_group_and_its_inversion(scene, method):
    obj = noisy_sphere()
    z = positions_of(obj.data)[:, 2]
    group = obj.vertex_groups.new(name="Keep")
    members = np.flatnonzero(z > 0.3)
    group.add(members[::2].tolist(), 1.0, "REPLACE")
    group.add(members[1::2].tolist(), 0.25, "REPLACE")  # any weight above 0 fixes
    group.add(np.flatnonzero(z < -0.5).tolist(), 0.0, "REPLACE")  # in the group with weight 0: moves
    fixed = np.zeros(len(z), dtype=bool)
    fixed[members] = True
    check_equals_core(obj, method, fixed=fixed, vertex_group="Keep")
    obj.modifiers.clear()
    check_equals_core(obj, method, fixed=~fixed, vertex_group="Keep", invert_vertex_group=True)


@pytest.mark.parametrize("method", CORE_METHOD)
def test_pin_boundary(scene, method):
    obj = noisy_grid()
    boundary = boundary_mask(obj.data)
    assert 0 < boundary.sum() < len(boundary)
    check_equals_core(obj, method, fixed=boundary, pin_boundary=True)


def test_pin_boundary_on_a_closed_mesh_fixes_nothing(scene):
    obj = noisy_sphere()
    check_equals_core(obj, "HC", pin_boundary=True)


def test_invert_without_a_group_fixes_nothing(scene):
    # As in the operators: Invert only means something with a group.
    check_equals_core(noisy_sphere(), "HC", invert_vertex_group=True)


# --- painted influence -----------------------------------------------------------------------------------


@pytest.mark.parametrize("method", CORE_METHOD)
@pytest.mark.parametrize("shape", MESHES)
def test_influence_group_equals_core(scene, shape, method):
    obj = MESHES[shape]()
    weights = painted(obj)
    check_equals_core(obj, method, influence=weights, influence_group="Paint")


@pytest.mark.parametrize("method", CORE_METHOD)
def test_inverted_influence_group_equals_core(scene, method):
    obj = noisy_sphere()
    weights = painted(obj)
    check_equals_core(obj, method, influence=inverted(weights), influence_group="Paint", invert_influence_group=True)


@pytest.mark.parametrize("method", CORE_METHOD)
def test_influence_with_a_fixed_group_and_a_pinned_boundary(scene, method):
    obj = noisy_grid()
    weights = painted(obj)
    keep = np.zeros(len(weights), dtype=bool)
    keep[40:80] = True  # fixed, whatever their influence (0, partial or 1)
    obj.vertex_groups.new(name="Keep").add(np.flatnonzero(keep).tolist(), 1.0, "REPLACE")
    fixed = keep | boundary_mask(obj.data)
    check_equals_core(
        obj, method, fixed=fixed, influence=weights, vertex_group="Keep", pin_boundary=True, influence_group="Paint"
    )


@pytest.mark.parametrize("method", CORE_METHOD)
def test_still_vertices_keep_their_bits_even_negative_zero(scene, method):
    obj = noisy_sphere()
    weights = painted(obj)
    fixed = np.zeros(len(weights), dtype=bool)
    fixed[::7] = True
    obj.vertex_groups.new(name="Keep").add(np.flatnonzero(fixed).tolist(), 1.0, "REPLACE")
    positions = positions_of(obj.data)
    positions[(weights == 0.0) | fixed, 0] = -0.0  # q + 0 would make it 0.0
    obj.data.vertices.foreach_set("co", positions.ravel())
    obj.data.update()
    check_equals_core(obj, method, fixed=fixed, influence=weights, vertex_group="Keep", influence_group="Paint")


def graph_distance(obj, source):
    """Edges from ``source`` to every vertex (inf where unreachable)."""
    edges = edges_of(obj.data)
    n = len(obj.data.vertices)
    graph = scipy.sparse.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    return scipy.sparse.csgraph.shortest_path(graph, directed=False, unweighted=True, indices=source)


@pytest.mark.parametrize("method", CORE_METHOD)
def test_full_influence_is_the_step_without_influence_bit_for_bit(scene, method):
    obj = noisy_sphere(subdivisions=4)
    group = obj.vertex_groups.new(name="Paint")
    group.add(list(range(len(obj.data.vertices))), 1.0, "REPLACE")
    modifier = add_modifier(obj, method=method, iterations=5)
    without = evaluated_positions(obj)
    inputs = module("nodes.inputs")
    inputs.set_input_attribute(modifier, "Influence", "Paint")
    assert np.array_equal(evaluated_positions(obj).view(np.uint32), without.view(np.uint32))
    # One vertex at half influence: vertices beyond its reach in 5 iterations (HC: two umbrellas each) keep the
    # bits of the step without influence, so weight 1 takes that step exactly, also when others are weighted.
    group.add([0], 0.5, "REPLACE")
    obj.data.update()
    got = evaluated_positions(obj)
    far = graph_distance(obj, 0) > 2 * 5 + 1
    assert far.sum() > len(far) // 4 and not np.array_equal(got, without)
    assert np.array_equal(got[far].view(np.uint32), without[far].view(np.uint32))


def test_missing_influence_group_keeps_every_vertex_and_is_reported(scene, capfd):
    # A name the mesh lacks reads as weight 0, everywhere.
    obj = noisy_sphere()
    before = positions_of(obj.data)
    add_modifier(obj, influence_group="Nowhere")
    assert "has no vertex group 'Nowhere' (the influence group): no vertex moves" in capfd.readouterr().out
    assert np.array_equal(evaluated_positions(obj), before)


def test_invert_influence_without_a_group_smooths_fully(scene):
    # As in the operators: Invert only means something with a group.
    check_equals_core(noisy_sphere(), "HC", invert_influence_group=True)


def test_zero_iterations_and_alpha_one_leave_the_mesh(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    modifier = add_modifier(obj, iterations=0)
    assert np.array_equal(evaluated_positions(obj), before)
    inputs = module("nodes.inputs")
    inputs.set_input(modifier, "Iterations", 10)
    for method in ("Laplacian, Central Point", "Laplacian, Original Point"):
        inputs.set_input(modifier, "Method", method)
        inputs.set_input(modifier, "Alpha", 1.0)  # keep all of the current / original point
        assert np.array_equal(evaluated_positions(obj), before), method


# --- adding it, names for scripts, one group per file ----------------------------------------------------


def test_operator_adds_to_every_selected_mesh_with_one_group(scene):
    a, b = noisy_sphere("A"), noisy_grid("B")
    bpy.ops.object.empty_add()
    empty = bpy.context.active_object
    select_only(a, b, empty)
    assert bpy.ops.object.hc_smooth_modifier_add(method="LAPLACIAN_ORIGINAL", iterations=4) == {"FINISHED"}
    assert bpy.ops.object.hc_smooth_modifier_add() == {"FINISHED"}  # a second one on each: the same group
    groups = {modifier.node_group for obj in (a, b) for modifier in obj.modifiers}
    assert len(groups) == 1 and [len(obj.modifiers) for obj in (a, b)] == [2, 2]
    assert [g.name for g in bpy.data.node_groups] == ["HC Smooth"]
    assert not hasattr(empty, "modifiers") or len(empty.modifiers) == 0
    inputs = module("nodes.inputs")
    first = a.modifiers[0]
    assert (inputs.get_input(first, "Iterations"), inputs.get_input(b.modifiers[1], "Iterations")) == (4, 10)
    method = inputs.get_input(first, "Method")
    assert method in ("Laplacian, Original Point", 3)  # its name in Blender 5, its number in 4.x


def test_operator_without_a_mesh_is_refused(scene):
    bpy.ops.object.empty_add()
    assert not bpy.ops.object.hc_smooth_modifier_add.poll()


def test_inputs_have_stable_names_and_scripts_can_set_them(scene):
    obj = noisy_sphere()
    modifier = add_modifier(obj, method="LAPLACIAN")
    group = modifier.node_group
    names = [item.name for item in group.interface.items_tree if item.item_type == "SOCKET" and item.in_out == "INPUT"]
    assert names == ["Geometry", *INPUT_NAMES]
    identifier = module("nodes.inputs").input_identifier(group, "Iterations")
    # What a script writes, without the add-on's helpers: an ID property in 4.x, RNA in Blender 5.
    if hasattr(modifier, "properties") and hasattr(modifier.properties, "inputs"):
        getattr(modifier.properties.inputs, identifier).value = 3
    else:
        modifier[identifier] = 3
    obj.update_tag()
    want = core.smooth(positions_of(obj.data), edges_of(obj.data), method="plain", iterations=3).positions
    assert np.abs(evaluated_positions(obj) - want).max() <= TOLERANCE * diagonal(want)


def test_older_group_is_rebuilt_in_place_keeping_settings(scene):
    hc_group = module("nodes.hc_group")
    obj = noisy_sphere()
    obj.vertex_groups.new(name="Keep").add(list(range(0, 40)), 1.0, "REPLACE")
    modifier = add_modifier(obj, method="HC", vertex_group="Keep", iterations=6)
    group = modifier.node_group
    group[hc_group.VERSION_KEY] = hc_group.VERSION - 1  # as saved by an older add-on
    group.nodes.remove(group.nodes[-1])  # whose nodes differ
    assert hc_group.ensure_group() == group
    assert group[hc_group.VERSION_KEY] == hc_group.VERSION and len(bpy.data.node_groups) == 1
    inputs = module("nodes.inputs")
    assert inputs.get_input(modifier, "Iterations") == 6
    assert inputs.get_input_attribute(modifier, "Fixed Group") == "Keep"
    fixed = np.zeros(len(obj.data.vertices), dtype=bool)
    fixed[:40] = True
    got, want = evaluated_positions(obj), expected(obj, "HC", fixed, iterations=6)
    assert np.abs(got - want).max() <= TOLERANCE * diagonal(want)


def as_version_1(group, version_key):
    """Make ``group`` what version 1 of the add-on built: no Invert Influence, Influence hidden and unused."""
    items = {item.name: item for item in group.interface.items_tree if item.item_type == "SOCKET"}
    group.interface.remove(items["Invert Influence"])
    if hasattr(items["Influence"], "hide_in_modifier"):
        items["Influence"].hide_in_modifier = True
    for link in list(group.links):
        if link.from_node.bl_idname == "NodeGroupInput" and link.from_socket.name == "Influence":
            to_socket = link.to_socket
            group.links.remove(link)
            to_socket.default_value = 1.0
    group[version_key] = 1


def test_version_1_group_is_upgraded_with_a_working_influence(scene):
    hc_group, inputs = module("nodes.hc_group"), module("nodes.inputs")
    obj = noisy_sphere()
    weights = painted(obj)
    modifier = add_modifier(obj, method="LAPLACIAN_ORIGINAL", iterations=6)
    group = modifier.node_group
    as_version_1(group, hc_group.VERSION_KEY)
    modifier.node_group = group  # the modifier's inputs follow the changed interface
    inputs.set_input_attribute(modifier, "Influence", "Paint")  # a script could set it: version 1 ignored it
    method = "LAPLACIAN_ORIGINAL"
    unweighted, weighted = expected(obj, method, iterations=6), expected(obj, method, influence=weights, iterations=6)
    tolerance = TOLERANCE * diagonal(weighted)
    assert np.abs(evaluated_positions(obj) - unweighted).max() <= tolerance
    assert hc_group.ensure_group() == group and group[hc_group.VERSION_KEY] == hc_group.VERSION > 1
    items = {item.name: item for item in group.interface.items_tree if item.item_type == "SOCKET"}
    assert "Invert Influence" in items and not getattr(items["Influence"], "hide_in_modifier", False)
    assert inputs.get_input_attribute(modifier, "Influence") == "Paint"
    assert (inputs.get_input(modifier, "Iterations"), inputs.get_input(modifier, "Invert Influence")) == (6, False)
    assert np.abs(evaluated_positions(obj) - weighted).max() <= tolerance
    assert np.abs(weighted - unweighted).max() > 100 * tolerance


def test_newer_group_is_used_as_it_is(scene):
    hc_group = module("nodes.hc_group")
    group = hc_group.ensure_group()
    group[hc_group.VERSION_KEY] = hc_group.VERSION + 1  # saved by a newer add-on: not ours to rebuild
    count = len(group.nodes)
    group.nodes.new("NodeFrame")
    assert hc_group.ensure_group() == group and len(group.nodes) == count + 1


def test_a_group_of_the_same_name_without_the_marker_is_left_alone(scene):
    theirs = bpy.data.node_groups.new("HC Smooth", "GeometryNodeTree")
    ours = module("nodes.hc_group").ensure_group()
    assert ours != theirs and len(theirs.nodes) == 0


# --- apply = operator; Add as Modifier ------------------------------------------------------------------


@pytest.mark.parametrize("influence", ["", "Paint"])
@pytest.mark.parametrize("method", CORE_METHOD)
def test_applying_gives_what_the_operator_gives(scene, method, influence):
    obj = noisy_grid("Patch")
    obj.vertex_groups.new(name="Keep").add(list(range(0, 30)), 1.0, "REPLACE")
    weights = painted(obj)
    before = positions_of(obj.data)
    settings = dict(
        method=method,
        alpha=ALPHA,
        beta=BETA,
        iterations=ITERATIONS,
        vertex_group="Keep",
        pin_boundary=True,
        influence_group=influence,
        invert_influence_group=method == "HC",
    )
    twin = obj.copy()
    twin.data = obj.data.copy()
    bpy.context.scene.collection.objects.link(twin)
    select_only(twin)
    assert bpy.ops.object.hc_smooth(**manual(**settings)) == {"FINISHED"}
    select_only(obj)
    assert bpy.ops.object.hc_smooth_modifier_add(**settings) == {"FINISHED"}
    assert bpy.ops.object.modifier_apply(modifier=obj.modifiers[-1].name) == {"FINISHED"}
    applied, smoothed = positions_of(obj.data), positions_of(twin.data)
    assert len(obj.modifiers) == 0
    assert np.abs(applied - smoothed).max() <= TOLERANCE * diagonal(smoothed)
    if influence:
        still = (inverted(weights) if settings["invert_influence_group"] else weights) == 0.0
        assert still[30:].any() and np.array_equal(applied[still], before[still])


@pytest.mark.parametrize("method", ["HC", "LAPLACIAN"])
@pytest.mark.parametrize(
    "transform",
    [
        dict(scale=(10.0, 10.0, 10.0)),
        dict(scale=(1.0, 1.0, 10.0), rotation_euler=(0.4, -0.3, 1.1)),
        dict(scale=(-2.0, 0.5, 3.0), rotation_euler=(1.2, 0.1, -0.7)),
    ],
    ids=["x10", "(1, 1, 10) rotated", "(-2, 0.5, 3) rotated"],
)
def test_the_deviation_limit_is_in_world_space_and_applying_gives_what_the_operator_gives(scene, method, transform):
    """A Deviation Limit of 0.01 on a scaled object: no vertex of the modifier's result moves more than 0.01
    in the world, and applying it gives what the operator gives; scaling the object again re-evaluates it."""
    obj = transformed(noisy_sphere(), **transform)
    before = positions_of(obj.data)
    limit = f32(0.01)
    settings = dict(method=method, alpha=ALPHA, beta=BETA, iterations=ITERATIONS, max_deviation=0.01)
    twin = obj.copy()
    twin.data = obj.data.copy()
    bpy.context.scene.collection.objects.link(twin)
    select_only(twin)
    assert bpy.ops.object.hc_smooth(**manual(**settings)) == {"FINISHED"}
    add_modifier(obj, **settings)
    got = evaluated_positions(obj)
    moves = np.linalg.norm(in_world(obj, got) - in_world(obj, before), axis=1)
    rounding = 4 * float(np.finfo(np.float32).eps) * float(np.abs(in_world(obj, before)).max())
    assert moves.max() <= limit + rounding and moves.max() > 0.99 * limit  # kept, and binding
    assert bpy.ops.object.modifier_apply(modifier=obj.modifiers[-1].name) == {"FINISHED"}
    applied, smoothed = positions_of(obj.data), positions_of(twin.data)
    assert np.abs(applied - smoothed).max() <= TOLERANCE * diagonal(smoothed)
    # The modifier follows the object's scale.
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    add_modifier(obj, **settings)
    transformed(obj, scale=tuple(2 * value for value in obj.scale))
    moves = np.linalg.norm(in_world(obj, evaluated_positions(obj)) - in_world(obj, before), axis=1)
    assert moves.max() <= limit + 2 * rounding and moves.max() > 0.99 * limit


def test_redo_panel_offers_add_as_modifier_with_the_same_settings(scene):
    obj = noisy_sphere()
    select_only(obj)
    # Called as a click does (invoked, with its undo step, see test_undo.py): then it is the last operator.
    bpy.ops.ed.undo_push(message="Before")
    bpy.ops.object.hc_smooth(
        "INVOKE_DEFAULT", True, **manual(method="LAPLACIAN_ORIGINAL", alpha=0.3, iterations=7, pin_boundary=True)
    )
    operator = bpy.context.window_manager.operators[-1]
    assert operator.bl_idname == "OBJECT_OT_hc_smooth"
    panel = redo_panel(operator)
    assert not panel.labels()
    ((idname, button),) = [entry for entry in panel.buttons() if entry[0] == "object.hc_smooth_modifier_add"]
    assert button.replace_smoothing is True
    assert (button.method, button.iterations, button.pin_boundary) == ("LAPLACIAN_ORIGINAL", 7, True)
    assert button.alpha == pytest.approx(0.3)
    operator.properties.mode = "SEQUENTIAL"  # the modifier cannot do that: the panel says so
    panel = redo_panel(operator)
    assert "The modifier runs Simultaneous mode" in panel.labels()
    operator.properties.mode = "SIMULTANEOUS"
    operator.properties.influence_group, operator.properties.invert_influence_group = "Paint", True
    panel = redo_panel(operator)
    assert not panel.labels()  # the modifier takes the influence group as it is
    ((idname, button),) = [entry for entry in panel.buttons() if entry[0] == "object.hc_smooth_modifier_add"]
    assert (button.influence_group, button.invert_influence_group) == ("Paint", True)


def test_modifier_operator_panel_shows_both_groups(scene):
    obj = noisy_sphere()
    select_only(obj)
    assert bpy.ops.object.hc_smooth_modifier_add("INVOKE_DEFAULT", True, influence_group="Paint") == {"FINISHED"}
    operator = bpy.context.window_manager.operators[-1]
    assert operator.bl_idname == "OBJECT_OT_hc_smooth_modifier_add"
    searched = [args[1] for args in (entry[1] for entry in redo_panel(operator).calls("prop_search"))]
    assert searched == ["vertex_group", "influence_group"]


def test_edit_mode_redo_panel_has_no_add_as_modifier(scene):
    noisy_sphere()
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.ed.undo_push(message="Before")
    bpy.ops.mesh.hc_smooth("INVOKE_DEFAULT", True, **manual(iterations=2))
    operator = bpy.context.window_manager.operators[-1]
    assert operator.bl_idname == "MESH_OT_hc_smooth"
    assert all(idname != "object.hc_smooth_modifier_add" for idname, _ in redo_panel(operator).buttons())
    bpy.ops.object.mode_set(mode="OBJECT")


def test_add_as_modifier_replaces_the_smoothing_just_made(scene):
    # As clicked in the UI: each operator invoked and pushing its undo step (see test_undo.py).
    obj = noisy_sphere()
    select_only(obj)
    before = positions_of(obj.data)
    bpy.ops.ed.undo_push(message="Before")
    settings = dict(method="HC", alpha=ALPHA, beta=BETA, iterations=ITERATIONS)
    assert bpy.ops.object.hc_smooth("INVOKE_DEFAULT", True, **manual(**settings)) == {"FINISHED"}
    smoothed = positions_of(bpy.data.objects["Sphere"].data)
    assert not np.array_equal(smoothed, before)
    assert bpy.ops.object.hc_smooth_modifier_add("INVOKE_DEFAULT", True, replace_smoothing=True, **settings) == {
        "FINISHED"
    }
    obj = bpy.data.objects["Sphere"]  # undo reloads the data: look it up again
    assert np.array_equal(positions_of(obj.data), before)  # the smoothing is gone...
    assert [modifier.name for modifier in obj.modifiers] == ["HC Smooth"]  # ...the modifier does it now
    assert np.abs(evaluated_positions(obj) - smoothed).max() <= TOLERANCE * diagonal(before)
    assert bpy.ops.ed.undo() == {"FINISHED"}  # one Ctrl+Z: back to before both
    obj = bpy.data.objects["Sphere"]
    assert len(obj.modifiers) == 0 and np.array_equal(positions_of(obj.data), before)


def test_add_as_modifier_after_a_property_edit_changes_nothing(scene):
    # An edited property pushes an undo step and is no operator: the smoothing is still the last operator (its
    # panel still shows), but one Ctrl+Z would take back the edit and leave the mesh smoothed for the modifier to
    # smooth again. Nothing is undone or added.
    obj = noisy_sphere()
    select_only(obj)
    bpy.ops.ed.undo_push(message="Before")
    settings = dict(method="HC", alpha=ALPHA, beta=BETA, iterations=ITERATIONS)
    assert bpy.ops.object.hc_smooth("INVOKE_DEFAULT", True, **manual(**settings)) == {"FINISHED"}
    smoothed = positions_of(bpy.data.objects["Sphere"].data)
    bpy.context.scene.hc_smooth.iterations = 33  # what the UI does when a field is edited: the edit, its step
    bpy.ops.ed.undo_push(message="Iterations")
    assert bpy.context.window_manager.operators[-1].bl_idname == "OBJECT_OT_hc_smooth"
    with pytest.raises(RuntimeError, match=r"Another change \('Iterations'\) came after HC Smooth"):
        bpy.ops.object.hc_smooth_modifier_add("INVOKE_DEFAULT", True, replace_smoothing=True, **settings)
    obj = bpy.data.objects["Sphere"]
    assert len(obj.modifiers) == 0 and np.array_equal(positions_of(obj.data), smoothed)
    assert bpy.context.scene.hc_smooth.iterations == 33  # the edit is kept


def test_add_as_modifier_undoes_only_the_smoothing(scene):
    obj = noisy_sphere()
    select_only(obj)
    bpy.ops.ed.undo_push(message="Before")
    bpy.context.scene.hc_smooth.pin_boundary = True  # an edit before the smoothing: it must stay
    bpy.ops.ed.undo_push(message="Pin Boundary")
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth("INVOKE_DEFAULT", True, **manual(iterations=3)) == {"FINISHED"}
    assert bpy.ops.object.hc_smooth_modifier_add("INVOKE_DEFAULT", True, replace_smoothing=True, iterations=3) == {
        "FINISHED"
    }
    obj = bpy.data.objects["Sphere"]
    assert len(obj.modifiers) == 1 and np.array_equal(positions_of(obj.data), before)
    assert bpy.context.scene.hc_smooth.pin_boundary


def test_replace_after_another_operation_only_adds(scene):
    obj = noisy_sphere()
    select_only(obj)
    before = positions_of(obj.data)
    bpy.ops.ed.undo_push(message="Before")
    bpy.ops.object.select_all("INVOKE_DEFAULT", True, action="SELECT")  # the last operation is not HC Smooth
    assert bpy.ops.object.hc_smooth_modifier_add("INVOKE_DEFAULT", True, replace_smoothing=True) == {"FINISHED"}
    obj = bpy.data.objects["Sphere"]
    assert len(obj.modifiers) == 1 and np.array_equal(positions_of(obj.data), before)


# --- the panel and the Add Modifier menu ------------------------------------------------------------------


def test_panel_button_and_add_modifier_menu_carry_the_scene_settings(scene):
    noisy_sphere()
    panel = module("ui.panel")
    settings = scene.hc_smooth
    settings.iterations, settings.method, settings.pin_boundary = 17, "LAPLACIAN_CENTRAL", True
    settings.influence_group, settings.invert_influence_group = "Paint", True
    settings.max_deviation = 0.02
    for draw in (
        lambda layout: bpy.types.VIEW3D_PT_hc_smooth.draw(type("P", (), {"layout": layout})(), bpy.context),
        lambda layout: panel.draw_modifier_menu_entry(type("M", (), {"layout": layout})(), bpy.context),
    ):
        layout = RecordingLayout()
        draw(layout)
        ((idname, button),) = [entry for entry in layout.buttons() if entry[0] == "object.hc_smooth_modifier_add"]
        assert (button.iterations, button.method, button.pin_boundary) == (17, "LAPLACIAN_CENTRAL", True)
        assert (button.influence_group, button.invert_influence_group) == ("Paint", True)
        assert button.max_deviation == pytest.approx(0.02)
    assert panel.draw_modifier_menu_entry in bpy.types.OBJECT_MT_modifier_add_deform._dyn_ui_initialize()
    settings.mode = "SEQUENTIAL"
    most = module("settings_spec").MODIFIER_MAX_ITERATIONS
    settings.iterations = 3 * most  # the mesh operators have no hard maximum; the modifier's operator clamps it
    layout = RecordingLayout()
    bpy.types.VIEW3D_PT_hc_smooth.draw(type("P", (), {"layout": layout})(), bpy.context)
    assert "The modifier runs Simultaneous mode" in layout.labels()
    assert f"The modifier runs at most {most} iterations" in layout.labels()
    ((idname, button),) = [entry for entry in layout.buttons() if entry[0] == "object.hc_smooth_modifier_add"]
    assert bpy.ops.object.hc_smooth_modifier_add(**vars(button)) == {"FINISHED"}  # the click
    modifier = bpy.context.active_object.modifiers[-1]
    assert module("nodes.inputs").get_input(modifier, "Iterations") == most


# --- a file with the modifier, opened without the add-on -------------------------------------------------


def test_saved_file_evaluates_the_same_without_the_add_on(scene, tmp_path):
    obj = noisy_grid("Patch")
    obj.vertex_groups.new(name="Keep").add(list(range(10, 50)), 1.0, "REPLACE")
    weights = painted(obj)
    add_modifier(obj, method="HC", vertex_group="Keep", pin_boundary=True, influence_group="Paint")
    with_add_on = evaluated_positions(obj)
    path = str(tmp_path / "with_modifier.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.preferences.addon_disable(module=ADDON)
    try:
        assert ADDON not in bpy.context.preferences.addons
        assert not hasattr(bpy.ops.object, "hc_smooth_modifier_add") or not hasattr(
            bpy.types, "OBJECT_OT_hc_smooth_modifier_add"
        )
        bpy.ops.wm.open_mainfile(filepath=path)
        reopened = evaluated_positions(bpy.data.objects["Patch"])
    finally:
        bpy.ops.preferences.addon_enable(module=ADDON)
    assert np.array_equal(reopened, with_add_on)
    fixed = np.zeros(len(reopened), dtype=bool)
    fixed[10:50] = True
    fixed |= boundary_mask(bpy.data.objects["Patch"].data)
    want = expected(bpy.data.objects["Patch"], "HC", fixed, influence=weights)
    assert np.abs(reopened - want).max() <= TOLERANCE * diagonal(want)


def test_moving_the_object_evaluates_the_modifier_again(scene):
    """Documented in docs/modifier.md, "Limits": the group reads its object's world matrix (Self Object), and
    Blender then evaluates it again on every move of the object, even a translation with no Deviation Limit and
    no Deviation Map; a Smooth modifier's object is only moved."""
    updates = []

    @bpy.app.handlers.persistent
    def record(scene, depsgraph):
        updates.extend(
            (update.id.name, update.is_updated_geometry) for update in depsgraph.updates if update.id.name in names
        )

    smoothed = noisy_sphere(name="Smoothed")
    select_only(smoothed)
    assert bpy.ops.object.hc_smooth_modifier_add(max_deviation=0.0, deviation_map=False) == {"FINISHED"}
    plain = noisy_sphere(name="Plain")
    plain.modifiers.new("Smooth", "SMOOTH")
    names = {"Smoothed", "Plain"}
    bpy.context.view_layer.update()
    bpy.app.handlers.depsgraph_update_post.append(record)
    try:
        for obj in (smoothed, plain):
            obj.location.x += 1.0
        bpy.context.view_layer.update()
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(record)
    assert ("Smoothed", True) in updates and ("Plain", False) in updates and ("Plain", True) not in updates
