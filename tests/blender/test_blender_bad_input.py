"""Every bad input gets a clear message, and every mesh stays bit-identical."""

import bpy
import numpy as np
import pytest
from blender_scene import make_mesh_object, noisy_sphere, positions_of, select_only


def snapshot():
    return {o.name: positions_of(o.data).tobytes() for o in bpy.data.objects if o.type == "MESH"}


def run_expecting(message, **properties):
    before = snapshot()
    with pytest.raises(RuntimeError, match=message):
        bpy.ops.object.hc_smooth(**properties)
    assert snapshot() == before


def test_no_mesh_selected(scene):
    empty = bpy.data.objects.new("Empty", None)
    scene.collection.objects.link(empty)
    select_only(empty)
    run_expecting("Select at least one mesh object.*empty")


def test_empty_mesh(scene):
    select_only(make_mesh_object("Nothing", []))
    run_expecting("has no vertices")


def test_mesh_without_edges_points_to_point_cloud_smoothing(scene):
    points = np.random.default_rng(0).normal(size=(50, 3))
    select_only(make_mesh_object("Scan", points))
    run_expecting("no edges.*point cloud.*hc_smooth_points")


def test_nan_coordinates(scene):
    obj = noisy_sphere()
    obj.data.name = "SphereData"  # the message names the object the user selected, as the others do
    positions = positions_of(obj.data)
    positions[5] = np.nan
    obj.data.vertices.foreach_set("co", positions.ravel())
    run_expecting(f"Object '{obj.name}' has 1 vertex with NaN or infinite.*vertex 5")


def test_missing_vertex_group(scene):
    noisy_sphere()
    run_expecting("no vertex group 'Nope'", vertex_group="Nope")


def test_one_bad_mesh_stops_all_before_anything_is_written(scene):
    good = noisy_sphere("Good")
    bad = make_mesh_object("Bad", np.random.default_rng(0).normal(size=(5, 3)))
    select_only(good, bad)
    run_expecting("Bad.*no edges")


def test_linked_library_mesh_cannot_be_edited(scene, tmp_path):
    noisy_sphere("Linked")
    library = tmp_path / "library.blend"
    bpy.data.libraries.write(str(library), {bpy.data.objects["Linked"]})
    bpy.ops.wm.read_homefile(use_empty=True)
    with bpy.data.libraries.load(str(library), link=True) as (data_from, data_to):
        data_to.objects = ["Linked"]
    obj = data_to.objects[0]
    bpy.context.scene.collection.objects.link(obj)
    select_only(obj)
    assert obj.library is not None
    run_expecting("linked from library.*Make Local")
