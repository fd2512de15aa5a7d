"""Nothing lost, nothing garbage: blown-up runs are never written, relative shape keys follow the key
that was smoothed, and every route (operator, chunked modal run, command line, core) gives one result."""

import sys

import bpy
import numpy as np
import pytest
import test_blender_progress as progress
from blender_scene import ADDON, edges_of, make_mesh_object, noisy_sphere, positions_of, select_only

import core


def bits(array):
    return np.ascontiguousarray(array).view(np.uint32)


def key_positions(key):
    buffer = np.empty(len(key.data) * 3, dtype=np.float32)
    key.data.foreach_get("co", buffer)
    return buffer.reshape(-1, 3)


REGION = r"alpha 0 and beta 0 blew up .*alpha > 0 and beta > 0\.5"


def test_object_mode_refuses_a_blown_up_run_and_writes_nothing(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    with pytest.raises(RuntimeError, match=REGION):  # how bpy.ops hands on an operator's error report
        bpy.ops.object.hc_smooth(auto_amount=False, alpha=0.0, beta=0.0, iterations=200)
    assert np.array_equal(bits(positions_of(obj.data)), bits(before))


def test_edit_mode_refuses_a_blown_up_run_and_stays_in_edit_mode(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    with pytest.raises(RuntimeError, match=REGION):
        bpy.ops.mesh.hc_smooth(auto_amount=False, alpha=0.0, beta=0.0, iterations=2000)
    assert obj.mode == "EDIT"
    bpy.ops.object.mode_set(mode="OBJECT")
    assert np.array_equal(bits(positions_of(obj.data)), bits(before))


def test_point_operator_refuses_a_blown_up_run(scene):
    rng = np.random.default_rng(5)
    points = rng.normal(size=(800, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    obj = make_mesh_object("Cloud", points)
    select_only(obj)
    before = positions_of(obj.data)
    with pytest.raises(RuntimeError, match=REGION):
        bpy.ops.object.hc_smooth_points(auto_amount=False, alpha=0.0, beta=0.0, iterations_per_round=100)
    assert np.array_equal(bits(positions_of(obj.data)), bits(before))


def sphere_with_relative_keys():
    """Basis <- Lift (relative to Basis) <- Twist (relative to Lift): two levels of relative keys."""
    obj = noisy_sphere()
    basis = obj.shape_key_add(name="Basis", from_mix=False)
    lift = obj.shape_key_add(name="Lift", from_mix=False)
    twist = obj.shape_key_add(name="Twist", from_mix=False)
    other = obj.shape_key_add(name="Other", from_mix=False)  # relative to Basis, not to Lift
    lift.relative_key, twist.relative_key = basis, lift
    positions = key_positions(basis)
    lift.data.foreach_set("co", (positions + [0, 0, 0.5]).astype(np.float32).ravel())
    twist.data.foreach_set("co", (positions + [0.25, 0, 0.5]).astype(np.float32).ravel())
    other.data.foreach_set("co", (positions * 1.5).astype(np.float32).ravel())
    return obj


def offsets(obj):
    keys = obj.data.shape_keys.key_blocks
    return {key.name: key_positions(key) - key_positions(key.relative_key) for key in keys if key.name != "Basis"}


@pytest.mark.parametrize("smoothed, moving", [("Basis", {"Lift", "Twist", "Other"}), ("Lift", {"Twist"})])
@pytest.mark.parametrize("route", ["object", "edit"])
def test_keys_relative_to_the_smoothed_key_move_with_it(scene, smoothed, moving, route):
    obj = sphere_with_relative_keys()
    keys = obj.data.shape_keys.key_blocks
    obj.active_shape_key_index = keys.find(smoothed)
    before = {key.name: key_positions(key) for key in keys}
    offsets_before = offsets(obj)
    if route == "object":
        assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=5) == {"FINISHED"}
    else:
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        assert bpy.ops.mesh.hc_smooth(auto_amount=False, iterations=5) == {"FINISHED"}
        bpy.ops.object.mode_set(mode="OBJECT")
    after = {key.name: key_positions(key) for key in keys}
    expected = core.hc_smooth(
        before[smoothed], edges_of(obj.data), alpha=float(np.float32(0.1)), beta=float(np.float32(0.6)), iterations=5
    )
    np.testing.assert_allclose(after[smoothed], expected, atol=1e-6)
    displacement = after[smoothed] - before[smoothed]
    assert np.abs(displacement).max() > 1e-3
    for name, positions in after.items():
        if name in moving:  # the same displacement: what the key adds on top of its relative key is kept
            np.testing.assert_allclose(positions - before[name], displacement, atol=1e-6)
        elif name != smoothed:
            assert np.array_equal(bits(positions), bits(before[name])), name
    for name, offset in offsets(obj).items():
        if name in moving:
            np.testing.assert_allclose(offset, offsets_before[name], atol=1e-6)


def test_command_line_moves_relative_keys_too(scene, addon, tmp_path):
    obj = sphere_with_relative_keys()
    obj.name = "Scan"
    obj.active_shape_key_index = 0
    keys = obj.data.shape_keys.key_blocks
    before = {key.name: key_positions(key) for key in keys}
    source = tmp_path / "keys.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    assert sys.modules[ADDON + ".cli"].main([str(source), "-o", str(tmp_path / "out")]) == 0
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "out" / "keys.blend"))
    keys = bpy.data.objects["Scan"].data.shape_keys.key_blocks
    displacement = key_positions(keys["Basis"]) - before["Basis"]
    assert np.abs(displacement).max() > 1e-3
    for name in ("Lift", "Twist", "Other"):
        np.testing.assert_allclose(key_positions(keys[name]) - before[name], displacement, atol=1e-6)


@pytest.mark.parametrize("mode", ["SIMULTANEOUS", "SEQUENTIAL"])
def test_every_route_gives_the_same_result_with_a_tolerance(scene, addon, tmp_path, mode):
    """F9/execute, the chunked modal runner, the command line and the core: bit for bit."""
    jobs, mesh_objects = sys.modules[ADDON + ".jobs.mesh"], sys.modules[ADDON + ".operators.mesh_objects"]
    tolerance = 2e-4  # the routes all take it (and alpha, beta) in single precision, as the operator does
    props = progress.settings(mode=mode, iterations=60, tolerance=tolerance)
    alpha, beta = float(np.float32(props.alpha)), float(np.float32(props.beta))
    obj = noisy_sphere(name="Scan")
    start = positions_of(obj.data)
    expected = core.smooth(
        start,
        edges_of(obj.data),
        method="hc",
        alpha=alpha,
        beta=beta,
        iterations=60,
        mode=mode.lower(),
        tolerance=float(np.float32(tolerance)),
    )
    assert expected.stopped_early and expected.iterations < 60
    for chunk in (None, 1, 4, 7):
        (job,) = [mesh_objects.make_job(obj, props)]
        list(jobs.run([job], props, chunk=chunk))
        assert np.array_equal(bits(job.result), bits(expected.positions)), chunk
        assert job.report.iterations == expected.iterations
    source = tmp_path / "scan.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    assert (
        sys.modules[ADDON + ".cli"].main(
            [
                str(source),
                "-o",
                str(tmp_path / "out"),
                "--mode",
                mode,
                "--iterations",
                "60",
                "--tolerance",
                repr(tolerance),
            ]
        )
        == 0
    )
    bpy.ops.wm.open_mainfile(filepath=str(source))
    obj = bpy.data.objects["Scan"]
    select_only(obj)
    assert bpy.ops.object.hc_smooth(auto_amount=False, mode=mode, iterations=60, tolerance=tolerance) == {"FINISHED"}
    assert np.array_equal(bits(positions_of(obj.data)), bits(expected.positions))
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "out" / "scan.blend"))
    assert np.array_equal(bits(positions_of(bpy.data.objects["Scan"].data)), bits(expected.positions))


class Broken(Exception):
    pass


def failing_work():
    yield 0.5
    raise Broken("a bug")


def test_modal_bug_removes_the_timer_and_abandons(capfd):
    operator, context, statuses = progress.modal_operator()
    operator.start_modal(context, failing_work())
    assert operator.modal(context, progress.TIMER) == {"RUNNING_MODAL"}
    assert operator.modal(context, progress.TIMER) == {"CANCELLED"}
    assert operator.abandoned and not operator.finished
    assert context.window_manager.calls[-2:] == ["timer_remove", "end"] and statuses[-1] is None
    ((level, message),) = operator.reports
    assert level == {"ERROR"} and "Broken: a bug" in message and "nothing was changed" in message
    assert "Traceback" in capfd.readouterr().err


def test_point_clouds_move_keys_relative_to_the_smoothed_key(scene):
    rng = np.random.default_rng(7)
    points = rng.normal(size=(1500, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    points += rng.normal(scale=0.02, size=points.shape)
    obj = make_mesh_object("Cloud", points)
    basis = obj.shape_key_add(name="Basis", from_mix=False)
    lift = obj.shape_key_add(name="Lift", from_mix=False)
    lift.data.foreach_set("co", (key_positions(basis) + [0, 0, 0.5]).astype(np.float32).ravel())
    obj.active_shape_key_index = 0
    select_only(obj)
    before = {key.name: key_positions(key) for key in (basis, lift)}
    assert bpy.ops.object.hc_smooth_points() == {"FINISHED"}
    displacement = key_positions(basis) - before["Basis"]
    assert np.abs(displacement).max() > 1e-3
    np.testing.assert_allclose(key_positions(lift) - before["Lift"], displacement, atol=1e-6)
    assert np.array_equal(positions_of(obj.data), key_positions(basis))


def test_status_lines_name_the_object_the_user_selected(scene, capfd):
    obj = noisy_sphere()
    obj.name, obj.data.name = "Scan", "Icosphere"
    assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=2) == {"FINISHED"}
    assert "HC on 'Scan': 2 iterations" in capfd.readouterr().out
    rng = np.random.default_rng(1)
    points = rng.normal(size=(600, 3))
    cloud = make_mesh_object("Points.001", points / np.linalg.norm(points, axis=1, keepdims=True))
    cloud.name = "Cloud"
    select_only(cloud)
    assert bpy.ops.object.hc_smooth_points() == {"FINISHED"}
    assert "HC Smooth Points on 'Cloud':" in capfd.readouterr().out
