"""Reading a vertex group in bulk (Geometry Nodes evaluation) agrees with Blender's own per-vertex API."""

import importlib

import bpy
import numpy as np
from blender_scene import ADDON, noisy_grid, select_only


def mesh_io():
    return importlib.import_module(f"{ADDON}.operators.mesh_io")


def members_by_blender(obj, group):
    return np.array([any(e.group == group.index and e.weight > 0.0 for e in v.groups) for v in obj.data.vertices])


def grid_with_group(rng):
    obj = noisy_grid(size=60)  # 3600 vertices: above the bulk path's minimum
    n = len(obj.data.vertices)
    assert n >= mesh_io()._BULK_MINIMUM
    group = obj.vertex_groups.new(name="Keep")
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
    assert np.array_equal(mesh_io()._weights_through_geometry_nodes(obj.data, "Keep") > 0, mask)
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
