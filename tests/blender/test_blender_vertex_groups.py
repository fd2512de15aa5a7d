"""Reading a vertex group in bulk (Geometry Nodes evaluation) agrees with Blender's own per-vertex API, whatever
the group's name: Geometry Nodes look a group up by name, and an attribute of that name comes first (built-in
ones such as "id" or "sharp_edge" whether the mesh has them or not, in Blender 4.x; the mesh's own always)."""

import importlib

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, edges_of, faces_of, noisy_grid, positions_of, select_only

import core

# Names of attributes: built in (read as zeros in 4.x even where the mesh lacks them), or on the grid itself.
ATTRIBUTE_NAMES = ("id", "material_index", "sharp_edge", ".sculpt_face_set", "position", ".select_vert", "UVMap")
ALPHA, BETA = float(np.float32(0.1)), float(np.float32(0.6))


def mesh_io():
    return importlib.import_module(f"{ADDON}.operators.mesh_io")


def members_by_blender(obj, group):
    return np.array([any(e.group == group.index and e.weight > 0.0 for e in v.groups) for v in obj.data.vertices])


def weights_by_blender(obj, group):
    return np.array([next((e.weight for e in v.groups if e.group == group.index), 0.0) for v in obj.data.vertices])


def grid_with_group(rng, name="Keep"):
    obj = noisy_grid(size=60)  # 3600 vertices: above the bulk path's minimum
    n = len(obj.data.vertices)
    assert n >= mesh_io()._BULK_MINIMUM
    group = obj.vertex_groups.new(name=name)
    assert group.name == name
    chosen = np.flatnonzero(rng.random(n) < 0.3)
    group.add(chosen[: len(chosen) // 2].tolist(), 0.7, "REPLACE")
    group.add(chosen[len(chosen) // 2 :].tolist(), 0.0, "REPLACE")  # in the group with weight 0: not fixed
    obj.vertex_groups.new(name="Other").add(list(range(0, n, 5)), 1.0, "REPLACE")
    return obj, group


def test_bulk_read_equals_the_per_vertex_api_and_leaves_nothing_behind(scene):
    obj, group = grid_with_group(np.random.default_rng(1))
    counts = (len(bpy.data.objects), len(bpy.data.node_groups), len(bpy.data.meshes))
    attributes = sorted(a.name for a in obj.data.attributes)
    mask = mesh_io().vertex_group_members(obj, group.index)
    assert np.array_equal(mask, members_by_blender(obj, group))
    assert 0 < mask.sum() < len(mask)
    assert np.array_equal(mesh_io()._weights_through_geometry_nodes(obj.data, group.index) > 0, mask)
    assert (len(bpy.data.objects), len(bpy.data.node_groups), len(bpy.data.meshes)) == counts
    assert sorted(a.name for a in obj.data.attributes) == attributes


def test_a_mesh_attribute_with_the_group_name_does_not_confuse_the_read(scene):
    obj, group = grid_with_group(np.random.default_rng(2))
    decoy = obj.data.attributes.new("Keep", "FLOAT", "POINT")  # Geometry Nodes would see this name twice
    if bpy.app.version < (5, 0, 0):
        assert decoy is None  # Blender 4.x refuses an attribute named like a vertex group
    else:
        decoy.data.foreach_set("value", np.ones(len(obj.data.vertices), dtype=np.float32))
    assert np.array_equal(mesh_io().vertex_group_members(obj, group.index), members_by_blender(obj, group))


def test_operator_keeps_the_bulk_read_group_fixed(scene):
    obj, group = grid_with_group(np.random.default_rng(3))
    select_only(obj)
    before = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", before)
    assert bpy.ops.object.hc_smooth(auto_amount=False, vertex_group="Keep", iterations=5) == {"FINISHED"}
    after = np.empty_like(before)
    obj.data.vertices.foreach_get("co", after)
    fixed = members_by_blender(obj, group)
    before, after = before.reshape(-1, 3), after.reshape(-1, 3)
    assert np.array_equal(after[fixed].view(np.uint32), before[fixed].view(np.uint32))
    assert np.any(after[~fixed] != before[~fixed])


@pytest.mark.parametrize("name", ATTRIBUTE_NAMES)
def test_groups_named_like_attributes_are_read_in_bulk(scene, name):
    obj, group = grid_with_group(np.random.default_rng(4), name)
    counts = (len(bpy.data.objects), len(bpy.data.node_groups), len(bpy.data.meshes))
    weights = mesh_io().vertex_group_weights(obj, group.index)
    assert np.array_equal(weights, weights_by_blender(obj, group).astype(np.float32))
    assert (weights == np.float32(0.7)).sum() > 100
    assert (len(bpy.data.objects), len(bpy.data.node_groups), len(bpy.data.meshes)) == counts
    assert [g.name for g in obj.vertex_groups] == [name, "Other"]  # the user's group keeps its name


def as_the_add_on(obj, before, **options):
    """core's run as the operator makes it with these numbers: welded, the open border free."""
    triangles = core.geometry.fan_triangles(np.array(faces_of(obj.data)))
    return core.smooth_mesh(
        before,
        edges_of(obj.data),
        faces=triangles,
        weld=True,
        border="free",
        alpha=ALPHA,
        beta=BETA,
        iterations=5,
        **options,
    )


@pytest.mark.parametrize("name", ATTRIBUTE_NAMES)
def test_operator_fixed_and_influence_groups_named_like_attributes(scene, name):
    obj, group = grid_with_group(np.random.default_rng(5), name)
    select_only(obj)
    before = positions_of(obj.data)
    weights = weights_by_blender(obj, group).astype(np.float32)
    fixed = weights > 0
    assert bpy.ops.object.hc_smooth(auto_amount=False, vertex_group=name, iterations=5) == {"FINISHED"}
    after = positions_of(obj.data)
    assert np.array_equal(after[fixed].view(np.uint32), before[fixed].view(np.uint32))
    assert np.array_equal(after, as_the_add_on(obj, before, fixed=fixed))
    obj.data.vertices.foreach_set("co", before.ravel())
    obj.data.update()
    assert bpy.ops.object.hc_smooth(auto_amount=False, influence_group=name, iterations=5) == {"FINISHED"}
    want = as_the_add_on(obj, before, influence=weights)
    assert np.array_equal(positions_of(obj.data), want) and not np.array_equal(want, before)


@pytest.mark.parametrize("name", ("Keep", *ATTRIBUTE_NAMES))
def test_modifier_reads_the_group_or_refuses_it(scene, name):
    # Geometry Nodes cannot be told to read the group rather than the attribute: the modifier's operator
    # refuses a group the modifier would not read, and an object whose group named "position" takes Set
    # Position's writes (Blender 5.2). The checks agree with what a modifier reading the group by name does.
    obj, group = grid_with_group(np.random.default_rng(6), name)
    select_only(obj)
    before = positions_of(obj.data)
    fixed = weights_by_blender(obj, group) > 0
    readable = mesh_io().group_read_by_name(obj, group.index)
    movable = mesh_io().geometry_nodes_move_vertices(obj)
    assert movable or name == "position"
    if name == "Keep":
        assert readable and movable
    if bpy.app.version < (5, 0, 0):  # built-in names first, present or not
        assert readable == (name == "Keep") and movable
    modifier = obj.modifiers.new("By hand", "NODES")  # what a user picking the group in the modifier gets
    modifier.node_group = importlib.import_module(f"{ADDON}.nodes.hc_group").ensure_group()
    importlib.import_module(f"{ADDON}.nodes.inputs").set_input_attribute(modifier, "Fixed Group", name)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    evaluated = positions_of(obj.evaluated_get(depsgraph).data)
    want = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=10, fixed=fixed)  # defaults
    assert (np.abs(evaluated - want).max() <= 1e-5 * np.linalg.norm(np.ptp(before, axis=0))) == (readable and movable)
    obj.modifiers.remove(modifier)
    for setting in ("vertex_group", "influence_group"):
        if readable and movable:
            assert bpy.ops.object.hc_smooth_modifier_add(**{setting: name}) == {"FINISHED"}
            obj.modifiers.remove(obj.modifiers[-1])
        else:
            problem = "named 'position'" if not movable else f"read the attribute '{name}', not the vertex group"
            with pytest.raises(RuntimeError, match=problem):
                bpy.ops.object.hc_smooth_modifier_add(**{setting: name})
            assert len(obj.modifiers) == 0
