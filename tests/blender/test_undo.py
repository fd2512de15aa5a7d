"""Ctrl+Z after each operator restores the scene bit for bit, through Blender's own undo stack.

Headless Blender starts without an undo stack (wm_file_read_post() in windowmanager/intern/wm_files.cc
only creates it `if (!G.background)`), so ed.undo's poll fails at first. But ed.undo_push creates the
stack on demand in background mode (ed_undo_push_exec() in editors/undo/ed_undo.cc: "Exception for
background mode, see: T60934"), and the bpy module has a window and a screen, so ed.undo, ed.redo and
ed.undo_redo pass their polls once the stack holds two steps. An operator called from Python pushes its
own undo step only with undo=True (the second positional argument of a bpy.ops call; otherwise
WM_operator_call_py() raises op_undo_depth around the call), which is what a click in the UI does.

So each test pushes the state before, runs the operator as the UI does, checks that it changed
something (else undo would be vacuous), presses Ctrl+Z (ed.undo) and compares every position and shape
key as bytes; then Ctrl+Shift+Z (ed.redo) must give back the result to the bit. Object mode and point
clouds go through the global (memfile) undo, Edit mode through the mesh undo system (memfile undo is
off while the active object is in Edit mode: ED_undo_is_memfile_compatible()). The `scene` fixture's
read_homefile frees the stack, so every test starts with an empty one. Not covered: the modal run with
a progress bar (interactive only; in background invoke() runs execute()).
"""

import bmesh
import bpy
import numpy as np
import pytest
from blender_scene import make_mesh_object, noisy_grid, noisy_sphere, select_only

HAS_POINT_CLOUD_CONVERT = "POINTCLOUD" in {
    item.identifier for item in bpy.ops.object.convert.get_rna_type().properties["target"].enum_items
}


def raw(array):
    return np.ascontiguousarray(array).tobytes()


def float_attribute(collection, attribute, count, width=3):
    buffer = np.empty(count * width, dtype=np.float32)
    collection.foreach_get(attribute, buffer)
    return raw(buffer)


def snapshot():
    """Everything the operators could touch, as bytes: positions of every mesh and point cloud, every
    shape key, which objects and data-blocks exist, modes and active keys."""
    for obj in bpy.context.scene.objects:
        if obj.mode == "EDIT":
            obj.update_from_editmode()  # Edit-mode data lives in BMesh until written back
    state = {
        "objects": sorted(
            (o.name, o.type, o.data.name if o.data else None, o.mode, o.active_shape_key_index)
            for o in bpy.data.objects
        ),
        "meshes": {},
        "keys": sorted(k.name for k in bpy.data.shape_keys),
        "point clouds": {},
    }
    for mesh in bpy.data.meshes:
        keys = None
        if mesh.shape_keys is not None:
            keys = [
                (k.name, k.relative_key.name, k.value, k.mute, float_attribute(k.data, "co", len(k.data)))
                for k in mesh.shape_keys.key_blocks
            ]
        edges = np.empty(len(mesh.edges) * 2, dtype=np.int32)
        mesh.edges.foreach_get("vertices", edges)
        state["meshes"][mesh.name] = (
            float_attribute(mesh.vertices, "co", len(mesh.vertices)),
            raw(edges),
            len(mesh.polygons),
            keys,
        )
    for cloud in bpy.data.pointclouds:
        state["point clouds"][cloud.name] = float_attribute(
            cloud.attributes["position"].data, "vector", len(cloud.points)
        )
    return state


def run_as_from_the_ui(operator, **properties):
    """Call the operator the way a click does: invoked, and pushing its own undo step (undo=True)."""
    assert operator("INVOKE_DEFAULT", True, **properties) == {"FINISHED"}


def ctrl_z():
    assert bpy.ops.ed.undo.poll(), "nothing to undo"
    assert bpy.ops.ed.undo() == {"FINISHED"}


def check_undo_restores(operator, changed, **properties):
    """Push the current state, run the operator, check it changed `changed` ("meshes", "keys", ...),
    undo and check everything is back to the bit; redo and check the result is back to the bit; undo
    again (the tests go on from the state before)."""
    bpy.ops.ed.undo_push(message="Before")
    before = snapshot()
    run_as_from_the_ui(operator, **properties)
    after = snapshot()
    for what in changed:
        assert after[what] != before[what], f"the operator did not change the {what}: nothing to undo"
    ctrl_z()
    assert snapshot() == before
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert snapshot() == after
    ctrl_z()
    assert snapshot() == before
    return before, after


def noisy_cloud(name="Scan", n=800, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    obj = make_mesh_object(name, (v + rng.normal(scale=0.01, size=v.shape)).astype(np.float32))
    select_only(obj)
    return obj


# Object mode (memfile undo)


def test_object_mode_undo_restores_the_mesh(scene):
    noisy_sphere()
    before, after = check_undo_restores(bpy.ops.object.hc_smooth, ["meshes"], iterations=4)
    assert after["keys"] == before["keys"] == []


def test_object_mode_undo_restores_the_active_shape_key(scene):
    obj = noisy_sphere()
    obj.shape_key_add(name="Basis", from_mix=False)
    obj.shape_key_add(name="Scan", from_mix=False)
    obj.active_shape_key_index = 1
    check_undo_restores(bpy.ops.object.hc_smooth, ["meshes"], iterations=4)


def test_object_mode_undo_restores_several_objects(scene):
    a, b = noisy_sphere("A", seed=1), noisy_grid("B")
    select_only(a, b)
    before, after = check_undo_restores(bpy.ops.object.hc_smooth, ["meshes"], iterations=3, pin_boundary=True)
    assert all(after["meshes"][name][0] != before["meshes"][name][0] for name in ("A", "B"))


def test_object_mode_undo_removes_the_new_shape_key(scene):
    noisy_sphere()
    before, after = check_undo_restores(bpy.ops.object.hc_smooth, ["meshes", "keys"], output="SHAPE_KEY", iterations=4)
    names = [k[0] for k in after["meshes"]["Sphere"][3]]
    assert names == ["Basis", "HC Smooth"] and before["meshes"]["Sphere"][3] is None


def test_object_mode_undo_removes_a_shape_key_added_to_existing_ones(scene):
    obj = noisy_sphere()
    obj.shape_key_add(name="Basis", from_mix=False)
    obj.shape_key_add(name="Scan", from_mix=False)
    obj.active_shape_key_index = 1
    before, after = check_undo_restores(bpy.ops.object.hc_smooth, ["meshes"], output="SHAPE_KEY", iterations=4)
    assert [k[0] for k in after["meshes"]["Sphere"][3]] == ["Basis", "Scan", "HC Smooth"]
    assert [k[0] for k in before["meshes"]["Sphere"][3]] == ["Basis", "Scan"]


# Edit mode (the mesh undo system)


def enter_edit_mode_as_from_the_ui(obj, select):
    """Tab into Edit mode with its undo step (as the UI pushes it), then select some vertices."""
    select_only(obj)
    bpy.ops.ed.undo_push(message="Object mode")
    assert bpy.ops.object.mode_set("EXEC_DEFAULT", True, mode="EDIT") == {"FINISHED"}
    bm = bmesh.from_edit_mesh(obj.data)
    for vertex in bm.verts:
        vertex.select_set(select(vertex.co))
    bm.select_flush_mode()
    bmesh.update_edit_mesh(obj.data)


@pytest.mark.parametrize("output", ["MESH", "SHAPE_KEY"])
def test_edit_mode_undo_restores_the_mesh(scene, output):
    obj = noisy_sphere()
    enter_edit_mode_as_from_the_ui(obj, lambda co: co.x > -0.2)
    before, after = check_undo_restores(bpy.ops.mesh.hc_smooth, ["meshes"], iterations=4, output=output)
    assert bpy.context.mode == "EDIT_MESH"
    if output == "SHAPE_KEY":
        assert before["meshes"]["Sphere"][3] is None
        assert [k[0] for k in after["meshes"]["Sphere"][3]] == ["Basis", "HC Smooth"]
    # Back in Object mode the mesh is still the one from before the operator.
    bpy.ops.object.mode_set(mode="OBJECT")
    state = snapshot()
    assert state["meshes"] == before["meshes"]


def test_edit_mode_undo_restores_the_active_shape_key(scene):
    obj = noisy_sphere()
    obj.shape_key_add(name="Basis", from_mix=False)
    obj.shape_key_add(name="Scan", from_mix=False)
    obj.active_shape_key_index = 1
    enter_edit_mode_as_from_the_ui(obj, lambda co: co.z > 0.0)
    check_undo_restores(bpy.ops.mesh.hc_smooth, ["meshes"], iterations=4)


# Point clouds (memfile undo)


def test_point_cloud_undo_restores_loose_vertices(scene):
    noisy_cloud()
    check_undo_restores(bpy.ops.object.hc_smooth_points, ["meshes"], rounds=2)


def test_point_cloud_undo_removes_the_rfs_mesh(scene):
    noisy_cloud()
    before, after = check_undo_restores(
        bpy.ops.object.hc_smooth_points, ["meshes", "objects"], rounds=2, keep_rfs_mesh=True
    )
    assert len(after["objects"]) == len(before["objects"]) + 1


@pytest.mark.skipif(not HAS_POINT_CLOUD_CONVERT, reason="this Blender cannot make point cloud objects")
def test_point_cloud_object_undo_restores_the_points(scene):
    noisy_cloud()
    assert bpy.ops.object.convert(target="POINTCLOUD") == {"FINISHED"}
    assert bpy.context.active_object.type == "POINTCLOUD"
    check_undo_restores(bpy.ops.object.hc_smooth_points, ["point clouds"], rounds=2)


# Adjust Last Operation (F9, the redo panel): undo to before the operator, run it again with the new values


@pytest.mark.parametrize("mode", ["OBJECT", "EDIT"])
def test_redo_panel_reruns_from_the_state_before(scene, mode):
    obj = noisy_sphere()
    if mode == "EDIT":
        enter_edit_mode_as_from_the_ui(obj, lambda co: True)
        operator = bpy.ops.mesh.hc_smooth
    else:
        bpy.ops.ed.undo_push(message="Before")
        operator = bpy.ops.object.hc_smooth
    before = snapshot()
    run_as_from_the_ui(operator, iterations=2)
    last = bpy.context.window_manager.operators[-1]
    assert last.bl_idname == operator.idname()
    last.properties.iterations = 6
    # The redo panel lives in a 3D viewport; ed.undo_redo without an area in the context crashes the
    # bpy module (segmentation fault, transform.translate too, 4.5 and 5.2). undo=True as for the
    # operator: the panel's button re-runs it outside any operator, so the re-run pushes its step.
    area = next(a for a in bpy.context.window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=bpy.context.window, area=area, region=region):
        assert bpy.ops.ed.undo_redo("EXEC_DEFAULT", True) == {"FINISHED"}
    adjusted = snapshot()
    ctrl_z()
    assert snapshot() == before
    run_as_from_the_ui(operator, iterations=6)
    assert snapshot() == adjusted
