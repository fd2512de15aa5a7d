"""Keep Sharp Edges through the operator, the N-panel's settings and the command line: each runs core's
Keep Sharp Edges with the numbers given, and the report says so."""

import math
import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, edges_of, faces_of, make_mesh_object, positions_of, select_only

import core

# Blender stores float properties in single precision: what the operator really gets.
ALPHA, BETA = float(np.float32(0.1)), float(np.float32(0.6))


def single(value):
    return float(np.float32(value))


def box_surface(cuts=8):
    """(positions, quads) of the surface of the cube [-1, 1]^3, ``cuts`` quads along each edge, welded."""
    t = np.linspace(-1.0, 1.0, cuts + 1)
    points, quads, index = [], [], {}

    def vertex(p):
        key = tuple(np.round(p, 9))
        if key not in index:
            index[key] = len(points)
            points.append(p)
        return index[key]

    for axis in range(3):
        for side in (-1.0, 1.0):
            u_axis, v_axis = [a for a in range(3) if a != axis]
            for i in range(cuts):
                for j in range(cuts):
                    corners = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = np.zeros(3)
                        p[axis], p[u_axis], p[v_axis] = side, t[i + di], t[j + dj]
                        corners.append(vertex(p))
                    quads.append(corners if side > 0 else corners[::-1])
    return np.array(points), quads


def noisy_box(name="Box", sigma=0.01, seed=3):
    positions, quads = box_surface()
    noise = np.random.default_rng(seed).normal(scale=sigma, size=positions.shape)
    obj = make_mesh_object(name, (positions + noise).astype(np.float32), faces=quads)
    select_only(obj)
    return obj


def core_run(before, obj, **options):
    """What the add-on hands core for a mesh (split vertices welded, the paper's border rule)."""
    triangles = core.geometry.fan_triangles(np.array(faces_of(obj.data)))
    return core.smooth_mesh(
        before, edges_of(obj.data), faces=triangles, weld=True, border="free", return_report=True, **options
    )


def test_the_operator_runs_core_keep_sharp_edges_with_its_automatic_amount(scene, capfd):
    obj = noisy_box()
    before = positions_of(obj.data)
    assert bpy.ops.object.hc_smooth(keep_sharp_edges=True) == {"FINISHED"}
    expected, report = core_run(before, obj, keep_sharp_edges=True, sharpness_angle=single(math.radians(30.0)))
    assert report.keep_sharp_edges and report.amount is not None and report.iterations >= 1
    np.testing.assert_allclose(positions_of(obj.data), expected, rtol=0, atol=1e-6)
    said = capfd.readouterr().out
    angle = round(math.degrees(report.sharpness_angle))
    assert f"Keep Sharp Edges on 'Box': sharpness {angle}\u00b0, automatic amount" in said
    assert f"{report.iterations} steps" in said and "iteration" not in said
    assert "Theorem 5.2" not in said  # HC's convergence region says nothing about this smoother


def test_explicit_steps_and_angle_run_as_set(scene):
    obj = noisy_box()
    before = positions_of(obj.data)
    angle = math.radians(40.0)
    assert bpy.ops.object.hc_smooth(keep_sharp_edges=True, sharpness_angle=angle, iterations=3) == {"FINISHED"}
    expected, report = core_run(
        before,
        obj,
        keep_sharp_edges=True,
        sharpness_angle=single(angle),
        alpha=ALPHA,
        beta=BETA,
        iterations=3,
        max_deviation=0.0,
    )
    assert report.iterations == 3 and report.amount is None
    assert np.array_equal(positions_of(obj.data), expected)


def dihedral_errors(positions, obj):
    """|angle - 90°| between the two faces at every crease of the box (edges between faces of different
    sides), in degrees: 0 for a perfect box."""
    triangles = core.geometry.fan_triangles(np.array(faces_of(obj.data)))
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    normals = np.cross(b - a, c - a)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    side = np.argmax(np.abs(normals), axis=1)  # the box side a face lies on (opposite sides share no edge)
    pairs = {}
    for f, tri in enumerate(triangles):
        for k in range(3):
            pairs.setdefault(tuple(sorted((tri[k], tri[(k + 1) % 3]))), []).append(f)
    crease = [fs for fs in pairs.values() if len(fs) == 2 and side[fs[0]] != side[fs[1]]]
    first, second = np.array(crease).T
    cosine = np.clip(np.einsum("ij,ij->i", normals[first], normals[second]), -1.0, 1.0)
    return np.abs(np.degrees(np.arccos(cosine)) - 90.0)


def test_keep_sharp_edges_keeps_the_box_creases_that_hc_rounds(scene):
    """The point of the option, through the operator: the box's 90° creases stay near 90°."""
    sharp, hc, sliding = noisy_box("Sharp"), noisy_box("Round"), noisy_box("Sliding")
    select_only(sharp)
    bpy.ops.object.hc_smooth(keep_sharp_edges=True)
    select_only(hc)
    bpy.ops.object.hc_smooth()
    select_only(sliding)
    bpy.ops.object.hc_smooth(keep_in_place=False)
    sharp_error = np.median(dihedral_errors(positions_of(sharp.data), sharp))
    hc_error = np.median(dihedral_errors(positions_of(hc.data), hc))
    sliding_error = np.median(dihedral_errors(positions_of(sliding.data), sliding))
    # HC's default keeps its moves across the surface, which rounds creases less than sliding does.
    assert sharp_error < 5.0 < sliding_error and sharp_error < hc_error < sliding_error


@pytest.fixture
def cli(addon):
    return sys.modules[ADDON + ".cli"]


def test_command_line_takes_the_angle_in_degrees(cli, scene, tmp_path, capsys):
    positions, quads = box_surface()
    positions = positions + np.random.default_rng(5).normal(scale=0.01, size=positions.shape)
    source = tmp_path / "box.obj"
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in positions.tolist()]
    lines += ["f " + " ".join(str(i + 1) for i in quad) for quad in quads]
    source.write_text("\n".join(lines) + "\n")
    argv = [str(source), "-o", str(tmp_path / "out"), "--keep-sharp-edges", "--sharpness-angle", "40"]
    assert cli.main(argv) == 0
    assert "Keep Sharp Edges, " in capsys.readouterr().out  # what ran: steps, not HC's iterations
    out = tmp_path / "out" / "box.obj"
    smoothed = np.array([line.split()[1:] for line in out.read_text().splitlines() if line.startswith("v ")], float)
    triangles = core.geometry.fan_triangles(quads)
    sides = np.array(quads)
    edges = np.concatenate([sides[:, [k, (k + 1) % 4]] for k in range(4)])  # the quads' sides, as Blender's
    expected = core.smooth_mesh(
        positions,
        edges,
        faces=triangles,
        weld=True,
        border="free",
        keep_sharp_edges=True,
        sharpness_angle=single(math.radians(40.0)),
    )
    np.testing.assert_array_equal(smoothed, expected)
    assert cli.main([str(source), "-o", str(tmp_path / "bad"), "--keep-sharp-edges", "--sharpness-angle", "180"]) == 2


def test_add_as_modifier_says_the_modifier_has_no_keep_sharp_edges(addon):
    draw = sys.modules[ADDON + ".operators.draw"]
    spec = sys.modules[ADDON + ".settings_spec"]
    line = "The modifier has no Keep Sharp Edges: it runs the method"
    assert line in draw.modifier_differences(spec.MeshSettings(keep_sharp_edges=True))
    assert line not in draw.modifier_differences(spec.MeshSettings())
