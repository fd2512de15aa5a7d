"""Painted influence: a vertex group's weights scale how far each vertex moves (operator, Edit mode,
command line), exactly as core's influence= does."""

import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, edges_of, noisy_sphere, positions_of, select_only

import core

ALPHA, BETA = float(np.float32(0.1)), float(np.float32(0.6))


def painted_sphere(subdivisions=3):
    """A noisy sphere with an "Influence" group: weight 0, 0.25, 0.5 or 1, and some vertices left out."""
    obj = noisy_sphere(subdivisions=subdivisions)
    group = obj.vertex_groups.new(name="Influence")
    rng = np.random.default_rng(2)
    weights = rng.choice([0.0, 0.25, 0.5, 1.0], size=len(obj.data.vertices)).astype(np.float32)
    left_out = rng.random(len(weights)) < 0.2  # not in the group: weight 0
    for value in (0.0, 0.25, 0.5, 1.0):
        group.add(np.flatnonzero((weights == value) & ~left_out).tolist(), float(value), "REPLACE")
    weights[left_out] = 0.0
    return obj, weights


@pytest.mark.parametrize("subdivisions", [3, 5])  # below and above the bulk (Geometry Nodes) reading
@pytest.mark.parametrize("invert", [False, True])
def test_operator_equals_core_with_the_group_weights(scene, subdivisions, invert):
    obj, weights = painted_sphere(subdivisions)
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth(
        auto_amount=False, iterations=6, influence_group="Influence", invert_influence_group=invert
    ) == {"FINISHED"}
    influence = 1.0 - weights if invert else weights
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=6, influence=influence)
    after = positions_of(obj.data)
    assert np.array_equal(after, expected)
    still = influence == 0
    assert still.any() and np.array_equal(after[still].view(np.uint32), before[still].view(np.uint32))
    assert not np.allclose(after[influence == 0.5], before[influence == 0.5])


def test_edit_mode_takes_the_influence_too(scene):
    obj, weights = painted_sphere()
    before = positions_of(obj.data)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    assert bpy.ops.mesh.hc_smooth(auto_amount=False, iterations=4, influence_group="Influence") == {"FINISHED"}
    bpy.ops.object.mode_set(mode="OBJECT")
    expected = core.hc_smooth(before, edges_of(obj.data), alpha=ALPHA, beta=BETA, iterations=4, influence=weights)
    assert np.array_equal(positions_of(obj.data), expected)


def test_missing_influence_group_changes_nothing(scene):
    obj = noisy_sphere()
    before = positions_of(obj.data)
    with pytest.raises(RuntimeError, match="no vertex group 'Paint' \\(the influence group\\)"):
        bpy.ops.object.hc_smooth(influence_group="Paint")
    assert np.array_equal(positions_of(obj.data), before)


def test_command_line_influence_group(scene, addon, tmp_path):
    obj, weights = painted_sphere()
    obj.name = "Scan"
    select_only(obj)
    before = positions_of(obj.data)
    source = tmp_path / "painted.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    cli = sys.modules[ADDON + ".cli"]
    assert (
        cli.main([str(source), "-o", str(tmp_path / "out"), "--influence-group", "Influence", "--iterations", "6"]) == 0
    )
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "out" / "painted.blend"))
    expected = core.hc_smooth(
        before, edges_of(bpy.data.objects["Scan"].data), alpha=ALPHA, beta=BETA, iterations=6, influence=weights
    )
    assert np.array_equal(positions_of(bpy.data.objects["Scan"].data), expected)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--invert-influence"], "--invert-influence needs --influence-group"),
        (["--points", "--influence-group", "Paint"], "--influence-group does not apply to point clouds"),
    ],
)
def test_command_line_refuses_influence_misuse(addon, tmp_path, capsys, argv, message):
    cli = sys.modules[ADDON + ".cli"]
    assert cli.main([str(tmp_path / "a.ply"), "-o", str(tmp_path / "out"), *argv]) == 2
    assert message in capsys.readouterr().err
