"""object.hc_smooth_points on loose-vertex meshes and point cloud objects."""

import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, make_mesh_object, positions_of, select_only

import core


def noisy_sphere_points(n=1500, sigma=0.01, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return (v + rng.normal(scale=sigma, size=v.shape)).astype(np.float32)


def rms(points):
    return float(np.sqrt(np.mean((np.linalg.norm(points, axis=1) - 1.0) ** 2)))


def cloud_object(name="Scan", n=1500, seed=0):
    obj = make_mesh_object(name, noisy_sphere_points(n, seed=seed))
    select_only(obj)
    return obj


def test_smooths_loose_vertices_like_the_core(scene):
    obj = cloud_object()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth_points(rounds=2) == {"FINISHED"}
    after = positions_of(obj.data)
    assert len(obj.data.edges) == 0 and len(after) == len(before)
    assert rms(after) < 0.8 * rms(before)
    # By default the steps and alpha follow the noise, as in the core. Blender stores float
    # properties in single precision: pass the beta the operator really got.
    expected = core.smooth_point_cloud(before, beta=float(np.float32(0.55)), rounds=2)
    assert np.array_equal(after, expected)


def test_manual_amount_uses_alpha_and_steps_as_set(scene):
    obj = cloud_object()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth_points(auto_amount=False, alpha=0.05, iterations_per_round=7, rounds=2) == {
        "FINISHED"
    }
    expected = core.smooth_point_cloud(
        before, alpha=float(np.float32(0.05)), beta=float(np.float32(0.55)), rounds=2, iterations_per_round=7
    )
    assert np.array_equal(positions_of(obj.data), expected)
    # Numbers the caller sets are used as set, with the Automatic Amount left on: Steps per Round alone
    # runs with the default alpha.
    obj.data.vertices.foreach_set("co", before.ravel())
    bpy.ops.object.hc_smooth_points(alpha=0.05, iterations_per_round=7, rounds=2)
    assert np.array_equal(positions_of(obj.data), expected)
    obj.data.vertices.foreach_set("co", before.ravel())
    bpy.ops.object.hc_smooth_points(rounds=2, iterations_per_round=5)
    expected = core.smooth_point_cloud(
        before, alpha=float(np.float32(0.01)), beta=float(np.float32(0.55)), rounds=2, iterations_per_round=5
    )
    assert np.array_equal(positions_of(obj.data), expected)


def test_automatic_amount_follows_the_noise(scene):
    # Nearly clean and sparse: a few steps with a strong pull; noisy: many steps, a weak pull. The
    # operator's defaults run the core's defaults, so its report is the core's.
    quiet = core.smooth_point_cloud(noisy_sphere_points(1500, 0.001), return_mesh=True)[1]
    loud = core.smooth_point_cloud(noisy_sphere_points(1500, 0.05), return_mesh=True)[1]
    assert quiet.iterations_per_round < loud.iterations_per_round and quiet.alpha > loud.alpha
    obj = cloud_object()
    assert bpy.ops.object.hc_smooth_points() == {"FINISHED"}
    assert rms(positions_of(obj.data)) < 0.6 * rms(noisy_sphere_points())  # noise 0.1x the spacing: ~50 % off


def test_redo_panel_greys_out_the_manual_amount(scene):
    class Layout:
        def __init__(self, record):
            self.record, self.active, self.use_property_split = record, True, False

        def column(self, **kwargs):
            return Layout(self.record)

        row = column

        def prop(self, data, name, **kwargs):
            self.record.append(("prop", name, self.active))

        def __getattr__(self, name):
            return lambda *args, **kwargs: None

    cloud_object()
    for automatic in (True, False):
        record = []
        # The operator's settings as it snapshots them, with a layout to draw into.
        props = sys.modules[f"{ADDON}.settings_spec"].PointSettings(auto_amount=automatic)
        props.layout = Layout(record)
        bpy.types.OBJECT_OT_hc_smooth_points.draw(props, bpy.context)
        shown = {entry[1]: entry[2] for entry in record if entry[0] == "prop"}
        assert shown["auto_amount"] and shown["beta"] and shown["rounds"]
        assert shown["alpha"] is (not automatic) and shown["iterations_per_round"] is (not automatic)


def test_fixed_vertex_group_and_inversion(scene):
    obj = cloud_object()
    group = obj.vertex_groups.new(name="Keep")
    members = np.flatnonzero(positions_of(obj.data)[:, 2] > 0.5)
    group.add(members.tolist(), 1.0, "REPLACE")
    before = positions_of(obj.data)
    bpy.ops.object.hc_smooth_points(vertex_group="Keep", rounds=3)
    after = positions_of(obj.data)
    inside = np.zeros(len(before), bool)
    inside[members] = True
    assert np.array_equal(after[inside], before[inside]) and np.any(after[~inside] != before[~inside])
    obj.data.vertices.foreach_set("co", before.ravel())
    bpy.ops.object.hc_smooth_points(vertex_group="Keep", invert_vertex_group=True, rounds=3)
    after = positions_of(obj.data)
    assert np.array_equal(after[~inside], before[~inside]) and np.any(after[inside] != before[inside])


def test_keep_rfs_mesh_adds_an_object(scene):
    obj = cloud_object()
    names = set(bpy.data.objects.keys())
    bpy.ops.object.hc_smooth_points(rounds=2, keep_rfs_mesh=True)
    (new,) = set(bpy.data.objects.keys()) - names
    rfs = bpy.data.objects[new]
    assert rfs.type == "MESH" and len(rfs.data.vertices) == len(obj.data.vertices)
    assert len(rfs.data.polygons) > len(obj.data.vertices)  # ~2 faces per point
    assert np.array_equal(positions_of(rfs.data), positions_of(obj.data))


def snapshot():
    return {o.name: positions_of(o.data).tobytes() for o in bpy.data.objects if o.type == "MESH"}


@pytest.mark.parametrize(
    "case, message",
    [
        ("edges", "has edges or faces.*object.hc_smooth"),
        ("empty", "no points"),
        # Fewer than three distinct points cannot form an RFS face: said as such, not as "scan lines?".
        ("single", "'Single' is a single point: nothing to smooth"),
        ("coincide", "All 100 points of 'Same' coincide: nothing to smooth"),
        ("two", "The 100 points of 'Two' lie at only 2 distinct positions: nothing to smooth"),
        ("line", "The 200 points of 'Line' lie on one straight line: no RFS face can form, nothing to smooth"),
        ("nan", "NaN or infinite.*point 7"),
        ("group", "no vertex group 'Nope'"),
        ("nothing", "Select a mesh of loose vertices or a point cloud"),
    ],
)
def test_bad_input_writes_nothing(scene, case, message):
    properties = {}
    if case == "edges":
        select_only(make_mesh_object("Wire", [(0, 0, 0), (1, 0, 0), (0, 1, 0)], edges=[(0, 1)]))
    elif case == "empty":
        select_only(make_mesh_object("Nothing", []))
    elif case == "single":
        select_only(make_mesh_object("Single", [(0.5, 0.5, 0.5)]))
    elif case == "coincide":
        select_only(make_mesh_object("Same", [(1, 2, 3)] * 100))
    elif case == "two":
        select_only(make_mesh_object("Two", [(1, 2, 3), (1, 2, 4)] * 50))
    elif case == "line":  # no advice to raise Reach or Gap: no setting makes a face of collinear points
        t = np.linspace(-1.0, 1.0, 200)
        select_only(make_mesh_object("Line", np.stack([t, 2.0 * t + 0.5, 0.25 - t], axis=1)))
    elif case == "nan":
        points = noisy_sphere_points(100)
        points[7] = np.nan
        select_only(make_mesh_object("Bad", points))
    elif case == "group":
        cloud_object()
        properties["vertex_group"] = "Nope"
    else:
        select_only()
    before = snapshot()
    with pytest.raises(RuntimeError, match=message) as raised:
        bpy.ops.object.hc_smooth_points(**properties)
    assert "scan lines" not in str(raised.value)
    assert snapshot() == before


def test_point_cloud_object(scene):
    cloud = bpy.data.pointclouds.new("Cloud")
    if not hasattr(cloud, "resize"):
        # Blender 4.x cannot add points to a point cloud from Python: check the empty one is refused.
        obj = bpy.data.objects.new("Cloud", cloud)
        scene.collection.objects.link(obj)
        select_only(obj)
        assert len(cloud.points) == 0
        with pytest.raises(RuntimeError, match="has no points"):
            bpy.ops.object.hc_smooth_points()
        return
    points = noisy_sphere_points(1500)
    cloud.resize(len(points))
    cloud.attributes["position"].data.foreach_set("vector", points.ravel())
    obj = bpy.data.objects.new("Cloud", cloud)
    scene.collection.objects.link(obj)
    select_only(obj)
    assert bpy.ops.object.hc_smooth_points(rounds=4) == {"FINISHED"}
    after = np.empty(len(points) * 3, np.float32)
    cloud.attributes["position"].data.foreach_get("vector", after)
    assert rms(after.reshape(-1, 3)) < 0.85 * rms(points)


def test_invoke_in_background_runs_execute(scene):
    obj = cloud_object()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth_points("INVOKE_DEFAULT", rounds=2) == {"FINISHED"}
    assert np.any(positions_of(obj.data) != before)


@pytest.mark.parametrize(
    "given, amount",
    [
        ([], {}),
        (["--alpha", "0.05"], {"alpha": 0.05, "iterations_per_round": 22}),
        (["--steps-per-round", "4"], {"alpha": 0.01, "iterations_per_round": 4}),
    ],
)
def test_command_line_points_use_the_automatic_amount_unless_alpha_or_steps_are_given(
    addon, scene, tmp_path, given, amount
):
    # blender -b -c hc_smooth --points runs the operator's functions: its automatic amount unless --alpha or
    # --steps-per-round is given, which (as the operator's toggle) uses both manual values.
    one_file, arguments = sys.modules[ADDON + ".cli.one_file"], sys.modules[ADDON + ".cli.arguments"]
    blend = sys.modules[ADDON + ".cli.blend"]
    obj = cloud_object()
    before = positions_of(obj.data)
    plan = arguments.parse(["cloud.ply", "-o", str(tmp_path), "--points", *given])
    outcome = one_file.Outcome(source="cloud", target="cloud")
    blend.smooth_point_clouds([obj], one_file.point_settings(plan), outcome)
    assert np.array_equal(positions_of(obj.data), core.smooth_point_cloud(before, **amount))
    _, report = core.smooth_point_cloud(before, return_mesh=True, **amount)
    assert outcome.rounds == [(report.rounds, report.iterations_per_round)]


def test_operator_and_functions_give_the_same_result(scene):
    # The operator is a thin shell over read_clouds/run/write with its properties as PointSettings.
    point_cloud = sys.modules[ADDON + ".operators.point_cloud"]
    obj = cloud_object()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth_points(rounds=2, beta=0.625) == {"FINISHED"}
    through_operator = positions_of(obj.data)
    obj.data.vertices.foreach_set("co", before.ravel())
    settings = point_cloud.PointSettings(rounds=2, beta=0.625)  # exact in float32, as the operator stores it
    clouds = point_cloud.read_clouds([obj], settings)
    for _ in point_cloud.run(clouds, settings):
        assert np.array_equal(positions_of(obj.data), before)  # nothing is written while it runs
    point_cloud.write(clouds, settings, bpy.context)
    assert np.array_equal(positions_of(obj.data), through_operator)
    assert not np.array_equal(through_operator, before)


def scan_lines(lines=12, per_line=300, gap=0.2, seed=0):
    """Nearly clean parallel lines, points 100x closer along a line than across: no RFS faces form."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, per_line)
    points = np.stack(np.broadcast_arrays(x[None, :], gap * np.arange(lines)[:, None], 0.0), axis=-1)
    return (points.reshape(-1, 3) + rng.normal(scale=1e-5, size=(lines * per_line, 3))).astype(np.float32)


def test_points_that_cannot_move_are_reported_with_what_to_change(scene, capfd):
    obj = make_mesh_object("Lines", scan_lines())
    select_only(obj)
    capfd.readouterr()
    assert bpy.ops.object.hc_smooth_points() == {"FINISHED"}
    output = capfd.readouterr()
    text = output.out + output.err
    assert "have no RFS faces and did not move" in text and "Raise Reach, Gap and Neighbours" in text
    # A surface sample does not get the warning.
    cloud_object()
    capfd.readouterr()
    bpy.ops.object.hc_smooth_points()
    output = capfd.readouterr()
    assert "have no RFS faces" not in output.out + output.err
