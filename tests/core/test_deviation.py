"""The deviation map (core.mesh.deviation) and the PLY vertex property that carries it (cli.formats).

The expected deviations are computed here: vertex normals summed triangle by triangle in a Python loop, the
displacement projected on them. The colours are checked against the ramp's anchors and its symmetry.
"""

import numpy as np
import pytest
import scan_files
from test_cli_arguments import load
from test_cli_formats import ENCODINGS, header, ply_values, smoothed

import core
from bench.primitives import grid, ico_sphere, with_noise
from core.mesh import deviation as deviation_module

formats = load("cli.formats")
FormatError = formats.FormatError


def loop_normals(positions, triangles):
    """Unit area-weighted vertex normals, one triangle at a time (zero where no triangle touches)."""
    sums = np.zeros((len(positions), 3))
    for a, b, c in triangles:
        cross = np.cross(positions[b] - positions[a], positions[c] - positions[a])
        sums[a] += cross
        sums[b] += cross
        sums[c] += cross
    lengths = np.linalg.norm(sums, axis=1)
    return np.array([s / length if length > 0 else s for s, length in zip(sums, lengths)])


def noisy_pair(part, seed=0):
    """(before, after): a noisy mesh and the same smoothed by HC."""
    before = with_noise(part, 0.3, "isotropic", seed=seed)[0].positions
    after = core.hc_smooth(before, part.edges, alpha=0.1, beta=0.6, iterations=10)
    return before, after


@pytest.mark.parametrize("part", [ico_sphere(3), grid()], ids=["sphere", "open grid of quads"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_deviation_is_the_move_along_the_input_normals(part, dtype):
    before, after = (array.astype(dtype) for array in noisy_pair(part))
    triangles = part.triangles()
    expected = np.einsum(
        "ij,ij->i", after.astype(np.float64) - before, loop_normals(before.astype(np.float64), triangles)
    )
    deviation = core.normal_deviation(before, after, part.faces)
    assert deviation.dtype == dtype and deviation.shape == (len(before),)
    tolerance = 1e-6 if dtype == np.float32 else 1e-12
    np.testing.assert_allclose(deviation, expected, rtol=0, atol=tolerance * np.abs(expected).max())
    assert np.abs(expected).max() > 0 and (expected > 0).any() and (expected < 0).any()
    # Normals the caller has give the same numbers; the map holds them.
    normals = core.mesh.metrics.measure_input(before, part.faces, closed=False).normals
    np.testing.assert_array_equal(core.normal_deviation(before, after, normals=normals), deviation)
    np.testing.assert_array_equal(core.deviation_map(before, after, part.faces).deviation, deviation)


def test_sign_is_outwards_positive():
    part = ico_sphere(2)
    deviation = core.normal_deviation(part.positions, part.positions * 1.01, part.faces)
    assert np.all(deviation > 0)
    assert np.all(core.normal_deviation(part.positions, part.positions * 0.99, part.faces) < 0)


def test_vertices_without_a_normal_get_zero():
    part = ico_sphere(2)
    loose = np.vstack([part.positions, [[5.0, 5.0, 5.0]]])
    moved = loose + 0.1
    deviation = core.normal_deviation(loose, moved, part.faces)
    assert deviation[-1] == 0.0 and np.all(deviation[:-1] != 0.0)
    assert np.all(core.normal_deviation(loose, moved) == 0.0)  # no faces at all


def test_bad_input_is_refused():
    part = ico_sphere(2)
    with pytest.raises(ValueError, match="same shape"):
        core.normal_deviation(part.positions, part.positions[:-1], part.faces)
    with pytest.raises(ValueError, match="normals"):
        core.normal_deviation(part.positions, part.positions, normals=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="do not exist"):
        core.normal_deviation(part.positions[:5], part.positions[:5], part.faces)


def test_extent_is_the_99th_percentile_of_the_moves():
    moves = np.linspace(0.01, 1.0, 100)
    deviation = np.r_[np.zeros(1000), moves, -moves * 0.5, 50.0]  # still vertices, then one spike
    extent = core.deviation_extent(deviation)
    magnitude = np.sort(np.abs(deviation[deviation != 0]))
    assert extent == magnitude[int(np.ceil(0.99 * magnitude.size)) - 1]  # a value of the data, spike excluded
    assert extent < 50.0 and extent in magnitude
    assert core.deviation_extent(np.zeros(10)) == 0.0 and core.deviation_extent([0.5]) == 0.5


def srgb(colors):
    return np.rint(colors[:, :3] * 255).astype(int).tolist()


def test_ramp_runs_blue_white_red_and_saturates():
    colors = core.deviation_colors(np.array([-5.0, -1.0, 0.0, 1.0, 5.0]), 1.0)
    assert colors.dtype == np.float32 and colors.shape == (5, 4) and np.all(colors[:, 3] == 1.0)
    anchors = deviation_module.RAMP_ANCHORS.astype(int).tolist()
    assert srgb(colors) == [anchors[0], anchors[0], anchors[3], anchors[-1], anchors[-1]]
    # Symmetric about 0: a move inwards gets the mirror colour of the same move outwards.
    values = np.linspace(0, 1, 50)
    out, back = core.deviation_colors(values, 1.0), core.deviation_colors(-values, 1.0)
    assert np.all(out[1:, 0] >= out[1:, 2]) and np.all(back[1:, 2] >= back[1:, 0])
    table = deviation_module._TABLES[False]
    index = np.rint(values * 127).astype(int)
    np.testing.assert_array_equal(out, table[127 + index])
    np.testing.assert_array_equal(back, table[127 - index])
    # Lightness falls away from 0 on both sides.
    lightness = core.deviation_colors(np.linspace(-1, 1, 255), 1.0)[:, :3].sum(axis=1)
    assert np.argmax(lightness) == 127
    assert np.all(np.diff(lightness[:128]) >= 0) and np.all(np.diff(lightness[127:]) <= 0)


def test_zero_extent_is_the_middle_colour():
    colors = core.deviation_colors(np.zeros(4), 0.0)
    assert srgb(colors) == [deviation_module.RAMP_ANCHORS[3].astype(int).tolist()] * 4


def test_linear_colours_are_the_srgb_ones_decoded():
    deviation = np.linspace(-2, 2, 101)
    encoded = core.deviation_colors(deviation, 1.5).astype(np.float64)
    linear = core.deviation_colors(deviation, 1.5, linear=True)
    decoded = np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(linear[:, :3], decoded[:, :3], atol=1e-6)
    assert np.all(linear[:, 3] == 1.0)


def test_map_and_its_legend():
    before, after = noisy_pair(ico_sphere(3))
    deviation_map = core.deviation_map(before, after, ico_sphere(3).faces)
    d = deviation_map.deviation
    assert deviation_map.extent == core.deviation_extent(d)
    assert (deviation_map.low, deviation_map.high) == (float(d.min()), float(d.max()))
    np.testing.assert_array_equal(deviation_map.colors, core.deviation_colors(d, deviation_map.extent))
    legend = deviation_map.legend(lambda x: f"{x * 1000:.2f} mm")
    e = deviation_map.extent * 1000
    assert legend.startswith(f"deviation map -{e:.2f} mm to +{e:.2f} mm (blue: inwards, red: outwards")
    # The extremes beyond the ramp are named; none beyond: none named.
    assert ("largest" in legend) == (max(-d.min(), d.max()) > deviation_map.extent)
    still = core.deviation_map(before, before, ico_sphere(3).faces)
    assert still.legend() == "deviation map -0 to +0 (blue: inwards, red: outwards)"


# --- the PLY vertex property ---------------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_ply_gets_the_property_and_keeps_every_other_value(encoding):
    data, positions, faces = scan_files.rich_ply(encoding)
    mesh = formats.parse(data, ".ply")
    result = smoothed(positions)
    deviation = np.linspace(-1, 1, len(positions)).astype(np.float32)
    out = formats.updated(mesh, result, {"hc_deviation": deviation})
    plain = formats.updated(mesh, result)
    # The header gains one line after the vertex's last property.
    lines, before_lines = header(out).splitlines(), header(plain).splitlines()
    face_line = next(i for i, line in enumerate(before_lines) if line.startswith(b"element face"))
    vertex_last = face_line - 1
    assert before_lines[vertex_last].startswith(b"property")
    assert lines == before_lines[: vertex_last + 1] + [b"property float hc_deviation"] + before_lines[vertex_last + 1 :]
    _, with_map = ply_values(out)
    _, without = ply_values(plain)
    np.testing.assert_array_equal(with_map["vertex"].pop("hc_deviation").astype(np.float32), deviation)
    assert with_map.keys() == without.keys()
    for element, properties in without.items():
        assert with_map[element].keys() == properties.keys()
        for name, values in properties.items():
            np.testing.assert_array_equal(with_map[element][name], values, err_msg=f"{element} {name}")
    if encoding != "ascii":
        assert len(out) == len(plain) + len(b"property float hc_deviation\n") + 4 * len(positions)
    # Written again (a result smoothed once more): the property is rewritten, not added twice.
    again = formats.updated(formats.parse(out, ".ply"), result, {"hc_deviation": -deviation})
    assert header(again) == header(out)
    np.testing.assert_array_equal(ply_values(again)[1]["vertex"]["hc_deviation"].astype(np.float32), -deviation)


def test_ply_header_line_endings_are_kept():
    data, positions, _ = scan_files.rich_ply("binary_little_endian")
    data = data[: data.index(b"end_header")].replace(b"\n", b"\r\n") + data[data.index(b"end_header") :]
    data = data.replace(b"end_header\n", b"end_header\r\n", 1)
    mesh = formats.parse(data, ".ply")
    out = formats.updated(mesh, smoothed(positions), {"hc_deviation": np.zeros(len(positions), np.float32)})
    assert b"property float hc_deviation\r\n" in header(out)
    assert formats.parse(out, ".ply").vertex.property("hc_deviation") is not None


def test_ply_property_of_another_type_is_refused():
    data, positions, _ = scan_files.rich_ply("ascii")
    mesh = formats.parse(data, ".ply")
    with pytest.raises(FormatError, match="flags is not a float"):
        formats.updated(mesh, smoothed(positions), {"flags": np.zeros(len(positions))})


def test_converted_ply_carries_the_property_and_obj_stl_refuse_it():
    data, positions, faces = scan_files.rich_ply("ascii")
    mesh = formats.parse(data, ".ply")
    deviation = np.arange(len(positions), dtype=np.float32)
    for source in (".obj", ".stl"):
        converted = formats.parse(formats.converted(mesh, smoothed(positions), source), source)
        with pytest.raises(FormatError, match="cannot hold vertex values"):
            formats.updated(converted, converted.positions, {"hc_deviation": deviation[: len(converted.positions)]})
    obj = formats.parse(formats.converted(mesh, smoothed(positions), ".obj"), ".obj")
    ply_bytes = formats.converted(obj, obj.positions.astype(np.float32), ".ply", {"hc_deviation": deviation})
    _, values = ply_values(ply_bytes)
    np.testing.assert_array_equal(values["vertex"]["hc_deviation"], deviation)
    with pytest.raises(FormatError, match="cannot hold vertex values"):
        formats.converted(mesh, smoothed(positions), ".stl", {"hc_deviation": deviation})
