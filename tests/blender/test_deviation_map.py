"""The deviation map (Deviation Map, --deviation-attribute): each vertex's signed move along its input normal
as the point attribute hc_deviation, its colours, its legend, and nothing at all when the option is off.

The expected values are computed here from the positions before and after, with vertex normals summed face
by face in this file (not core's code): the attribute must equal the displacement's normal component.
"""

import bmesh
import bpy
import numpy as np
import pytest
from blender_scene import (
    ADDON,
    in_world,
    make_mesh_object,
    noisy_grid,
    noisy_sphere,
    positions_of,
    select_only,
    transformed,
)
from test_undo import ctrl_z, run_as_from_the_ui

import core

ATTRIBUTE, COLORS = "hc_deviation", "hc_deviation_color"


def area_weighted_normals(positions, triangles):
    """Unit vertex normals: the sum of the cross products (twice the area times the unit normal) of the
    triangles at each vertex, normalised; zero for a vertex no triangle touches."""
    positions = positions.astype(np.float64)
    sums = np.zeros_like(positions)
    for a, b, c in triangles:
        cross = np.cross(positions[b] - positions[a], positions[c] - positions[a])
        for vertex in (a, b, c):
            sums[vertex] += cross
    lengths = np.linalg.norm(sums, axis=1, keepdims=True)
    return np.divide(sums, lengths, out=np.zeros_like(sums), where=lengths > 0)


def triangles_of(mesh):
    """Each face as a fan from its first corner (the triangles the operators measure normals on)."""
    return [
        (p.vertices[0], p.vertices[k], p.vertices[k + 1]) for p in mesh.polygons for k in range(1, len(p.vertices) - 1)
    ]


def expected_deviation(before, after, triangles):
    return np.einsum("ij,ij->i", after.astype(np.float64) - before, area_weighted_normals(before, triangles))


def attribute_values(mesh, name=ATTRIBUTE):
    attribute = mesh.attributes[name]
    assert (attribute.domain, attribute.data_type) == ("POINT", "FLOAT")
    values = np.empty(len(mesh.vertices), dtype=np.float32)
    attribute.data.foreach_get("value", values)
    return values


def colors_of(mesh, name=COLORS):
    attribute = mesh.attributes[name]
    assert (attribute.domain, attribute.data_type) == ("POINT", "FLOAT_COLOR")
    values = np.empty(4 * len(mesh.vertices), dtype=np.float32)
    attribute.data.foreach_get("color", values)
    return values.reshape(-1, 4)


def attribute_names(mesh):
    """The attributes a user sees (Blender's internal ones start with a dot: selection, UV map layers)."""
    return sorted(attribute.name for attribute in mesh.attributes if not attribute.name.startswith("."))


def check_map(mesh, before, triangles, names=(ATTRIBUTE, COLORS), shown=True):
    """hc_deviation (or the ``names`` given) is the move along the input's normals; the colours are core's ramp
    of it, the active colours where ``shown`` (a mesh without colours of its own)."""
    after = positions_of(mesh)
    assert not np.array_equal(after, before), "nothing moved: the map would be vacuous"
    values = attribute_values(mesh, names[0])
    expected = expected_deviation(before, after, triangles)
    scale = np.abs(expected).max()
    assert scale > 0
    np.testing.assert_allclose(values, expected, rtol=0, atol=1e-5 * scale)
    extent = core.deviation_extent(values)
    np.testing.assert_array_equal(colors_of(mesh, names[1]), core.deviation_colors(values, extent, linear=True))
    assert (mesh.color_attributes.active_color_name == names[1]) is shown
    # Outwards is red, inwards blue.
    colors = colors_of(mesh, names[1])
    assert np.all(colors[values > extent / 2, 0] > colors[values > extent / 2, 2])
    assert np.all(colors[values < -extent / 2, 2] > colors[values < -extent / 2, 0])
    return values


def test_object_mode_stores_the_move_along_the_normals(scene, capfd):
    obj = noisy_sphere(sigma=0.05)
    before = positions_of(obj.data)
    triangles = triangles_of(obj.data)
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}
    values = check_map(obj.data, before, triangles)
    extent = core.deviation_extent(values)
    # The report's legend is the colours' range, in the scene's units (metres by default).
    said = capfd.readouterr().out
    assert "deviation map -" in said and "(blue: inwards, red: outwards" in said
    shown = bpy.utils.units.to_string("METRIC", "LENGTH", extent, precision=3)
    assert f"deviation map -{shown} to +{shown}" in said


@pytest.mark.parametrize("modifier", [False, True])
def test_a_scaled_objects_map_and_legend_are_in_world_space(scene, capfd, modifier):
    """On an object scaled (1, 1, 10) and rotated the map is the world-space move along the world-space
    normals, and the legend gives its range in scene units; the modifier's map is the same."""
    obj = transformed(noisy_sphere(sigma=0.05), scale=(1.0, 1.0, 10.0), rotation_euler=(0.4, -0.3, 1.1))
    before, triangles = positions_of(obj.data), triangles_of(obj.data)
    if modifier:
        add_modifier(obj, deviation_map=True, alpha=0.1, iterations=6)
        mesh = evaluated(obj)
    else:
        assert bpy.ops.object.hc_smooth(deviation_map=True, auto_amount=False, iterations=6) == {"FINISHED"}
        mesh = obj.data
    after = positions_of(mesh)
    values = attribute_values(mesh)
    expected = expected_deviation(in_world(obj, before), in_world(obj, after), triangles)
    np.testing.assert_allclose(values, expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    if not modifier:
        extent = core.deviation_extent(values)
        shown = bpy.utils.units.to_string("METRIC", "LENGTH", extent, precision=3)
        assert f"deviation map -{shown} to +{shown}" in capfd.readouterr().out


def test_off_adds_nothing(scene, capfd):
    obj = noisy_sphere(sigma=0.05)
    names = attribute_names(obj.data)
    active = obj.data.color_attributes.active_color_name
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    assert attribute_names(obj.data) == names and ATTRIBUTE not in names and COLORS not in names
    assert obj.data.color_attributes.active_color_name == active
    assert "deviation map" not in capfd.readouterr().out


def test_solid_shading_shows_the_colours(scene):
    # The bpy module has a screen (and a 3D Viewport): the shading is switched there as in the UI.
    spaces = [s for a in bpy.context.screen.areas for s in a.spaces if s.type == "VIEW_3D"]
    assert spaces
    for space in spaces:
        space.shading.color_type = "MATERIAL"
    noisy_sphere(sigma=0.05)
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    assert {space.shading.color_type for space in spaces} == {"MATERIAL"}  # off: the view is left alone
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}
    assert {space.shading.color_type for space in spaces} == {"VERTEX"}


def test_without_a_screen_nothing_fails(addon):
    # A context without a screen (a script in a timer, a server): the map is stored, the view not touched.
    module = __import__(ADDON + ".operators.mesh_smooth", fromlist=["show_attribute_colors"])
    module.show_attribute_colors(type("Context", (), {"screen": None})())


def test_several_objects_and_shape_key_output(scene, capfd):
    sphere = noisy_sphere(sigma=0.05)
    grid = noisy_grid()
    select_only(sphere, grid)
    befores = {obj.name: (positions_of(obj.data), triangles_of(obj.data)) for obj in (sphere, grid)}
    assert bpy.ops.object.hc_smooth(deviation_map=True, output="SHAPE_KEY") == {"FINISHED"}
    for obj in (sphere, grid):
        before, triangles = befores[obj.name]
        after = positions_of(obj.data)
        np.testing.assert_array_equal(after, before)  # the result went into the shape key
        key = obj.data.shape_keys.key_blocks[-1]
        smoothed = np.empty(3 * len(key.data), dtype=np.float32)
        key.data.foreach_get("co", smoothed)
        expected = expected_deviation(before, smoothed.reshape(-1, 3), triangles)
        np.testing.assert_allclose(attribute_values(obj.data), expected, atol=1e-5 * np.abs(expected).max())
    said = capfd.readouterr().out
    assert "'Sphere': deviation map -" in said and "'Grid': deviation map -" in said


def test_edit_mode_maps_the_selection(scene):
    obj = noisy_sphere(sigma=0.05)
    before = positions_of(obj.data)
    triangles = triangles_of(obj.data)
    select_only(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    for vertex in bm.verts:
        vertex.select_set(vertex.co.z > 0.0)
    bm.select_flush_mode()
    bmesh.update_edit_mesh(obj.data)
    assert bpy.ops.mesh.hc_smooth(deviation_map=True) == {"FINISHED"}
    assert bpy.context.mode == "EDIT_MESH"
    bpy.ops.object.mode_set(mode="OBJECT")
    values = check_map(obj.data, before, triangles)
    assert np.all(values[before[:, 2] <= 0.0] == 0.0)  # unselected vertices stay: no move


def test_object_mode_undo_removes_the_attributes(scene):
    obj = noisy_sphere(sigma=0.05)
    names, before = attribute_names(obj.data), positions_of(obj.data)
    bpy.ops.ed.undo_push(message="Before")
    run_as_from_the_ui(bpy.ops.object.hc_smooth, deviation_map=True)
    assert ATTRIBUTE in attribute_names(bpy.data.objects["Sphere"].data)
    ctrl_z()
    mesh = bpy.data.objects["Sphere"].data  # undo reloads the data
    assert attribute_names(mesh) == names
    np.testing.assert_array_equal(positions_of(mesh), before)


def test_edit_mode_undo_removes_the_attributes(scene):
    obj = noisy_sphere(sigma=0.05)
    names, before = attribute_names(obj.data), positions_of(obj.data)
    select_only(obj)
    bpy.ops.ed.undo_push(message="Object mode")
    assert bpy.ops.object.mode_set("EXEC_DEFAULT", True, mode="EDIT") == {"FINISHED"}
    bpy.ops.mesh.select_all(action="SELECT")
    run_as_from_the_ui(bpy.ops.mesh.hc_smooth, deviation_map=True)
    obj.update_from_editmode()
    assert ATTRIBUTE in attribute_names(obj.data)
    ctrl_z()
    assert bpy.context.mode == "EDIT_MESH"
    bpy.ops.object.mode_set(mode="OBJECT")  # the mesh as Edit mode writes it back
    mesh = bpy.data.objects["Sphere"].data
    assert attribute_names(mesh) == names
    np.testing.assert_array_equal(positions_of(mesh), before)


def attribute_data(mesh, name):
    """(domain, type, values) of an attribute, its values read through its type's own property."""
    attribute = mesh.attributes[name]
    prop = {"FLOAT2": "vector", "INT": "value", "BYTE_COLOR": "color", "FLOAT": "value"}[attribute.data_type]
    width = {"vector": 2, "color": 4}.get(prop, 1)
    values = np.empty(width * len(attribute.data), dtype=np.int32 if attribute.data_type == "INT" else np.float32)
    attribute.data.foreach_get(prop, values)
    return attribute.domain, attribute.data_type, values


def vertex_group_weights(obj, name):
    group = obj.vertex_groups[name]
    return [(v.index, g.weight) for v in obj.data.vertices for g in v.groups if g.group == group.index]


def test_an_earlier_map_is_replaced_and_no_names_pile_up(scene):
    obj = noisy_sphere(sigma=0.05)
    assert obj.data.color_attributes.default_color_name == ""  # no colours of its own
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}
    names = attribute_names(obj.data)
    before, triangles = positions_of(obj.data), triangles_of(obj.data)
    assert bpy.ops.object.hc_smooth(deviation_map=True, auto_amount=False, iterations=3) == {"FINISHED"}
    assert attribute_names(obj.data) == names  # written into the same two attributes
    check_map(obj.data, before, triangles)
    assert obj.data.color_attributes.default_color_name == COLORS  # its only colours: also the render colours


@pytest.mark.parametrize("name", [ATTRIBUTE, COLORS])
def test_a_vertex_group_of_a_maps_name_keeps_it_on_every_object(scene, capfd, name):
    """A vertex group named like the map (Geometry Nodes read it as an attribute of that name): every selected
    mesh is smoothed and mapped, the map under the next free name, the group as it was, nothing stray."""
    sphere, grid = noisy_sphere(sigma=0.05), noisy_grid()
    grid.vertex_groups.new(name=name).add([0, 5, 9], 0.75, "REPLACE")
    weights = vertex_group_weights(grid, name)
    select_only(sphere, grid)
    befores = {obj.name: (positions_of(obj.data), triangles_of(obj.data)) for obj in (sphere, grid)}
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}
    check_map(sphere.data, *befores["Sphere"])
    moved = (f"{ATTRIBUTE}.001", COLORS) if name == ATTRIBUTE else (ATTRIBUTE, f"{COLORS}.001")
    check_map(grid.data, *befores["Grid"], names=moved)
    assert sorted(set(attribute_names(grid.data)) - set(moved)) == sorted(
        set(attribute_names(sphere.data)) - {ATTRIBUTE, COLORS}
    )  # no stray map attribute beside them
    assert [group.name for group in grid.vertex_groups] == [name] and vertex_group_weights(grid, name) == weights
    said = capfd.readouterr().out
    assert "'Grid': deviation map -" in said and f"stored in '{moved[0]}' and '{moved[1]}'" in said
    assert said.count("stored in") == 1  # the sphere's went where it always goes


def test_user_attributes_of_the_maps_names_are_kept_and_so_is_the_render_colour(scene, capfd):
    """A UV map named hc_deviation, an integer face attribute named hc_deviation_color, the scan's own colours
    as the render colour: all stay as they were; the map goes to the next free names and says so."""
    obj = noisy_sphere(sigma=0.05)
    mesh = obj.data
    uv = mesh.uv_layers.new(name=ATTRIBUTE)
    uv_values = np.random.default_rng(5).random(2 * len(mesh.loops)).astype(np.float32)
    uv.data.foreach_set("uv", uv_values)
    faces = mesh.attributes.new(COLORS, "INT", "FACE")
    faces.data.foreach_set("value", np.arange(len(mesh.polygons), dtype=np.int32))
    scan = mesh.color_attributes.new("Col", "BYTE_COLOR", "POINT")
    scan.data.foreach_set("color", np.random.default_rng(6).random(4 * len(mesh.vertices)).astype(np.float32))
    mesh.color_attributes.active_color_name = mesh.color_attributes.default_color_name = "Col"
    kept = {name: attribute_data(mesh, name) for name in (ATTRIBUTE, COLORS, "Col")}
    uv_maps = [layer.name for layer in mesh.uv_layers]
    before, triangles = positions_of(mesh), triangles_of(mesh)
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}
    for name, (domain, data_type, values) in kept.items():
        got = attribute_data(mesh, name)
        assert got[:2] == (domain, data_type) and np.array_equal(got[2], values), name
    assert [layer.name for layer in mesh.uv_layers] == uv_maps
    moved = (f"{ATTRIBUTE}.001", f"{COLORS}.001")
    check_map(mesh, before, triangles, names=moved, shown=False)
    assert mesh.color_attributes.default_color_name == "Col"  # renders and exporters keep the scan's colours
    assert f"stored in '{moved[0]}' and '{moved[1]}'" in capfd.readouterr().out
    # Run again: the same two attributes take the new map.
    names = attribute_names(mesh)
    assert bpy.ops.object.hc_smooth(deviation_map=True, auto_amount=False, iterations=2) == {"FINISHED"}
    assert attribute_names(mesh) == names


def test_the_users_active_and_render_colours_stay_as_they_were(scene, capfd):
    """A scan with colours of its own (one the render colour, another the active one, as the user chose): the
    map leaves both choices alone, the viewport's shading too, and the report says where to pick the map."""
    obj = noisy_sphere(sigma=0.05)
    mesh = obj.data
    for name in ("Col", "Paint"):
        mesh.color_attributes.new(name, "BYTE_COLOR", "POINT")
    mesh.color_attributes.default_color_name, mesh.color_attributes.active_color_name = "Col", "Paint"
    before, triangles = positions_of(mesh), triangles_of(mesh)
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}
    check_map(mesh, before, triangles, shown=False)
    assert (mesh.color_attributes.default_color_name, mesh.color_attributes.active_color_name) == ("Col", "Paint")
    said = capfd.readouterr().out
    assert f"'{COLORS}' is under Color Attributes" in said


def test_a_mesh_without_faces_maps_zero(scene):
    # Loose edges have no normals: every vertex's deviation is 0 (and the colours the ramp's middle).
    rng = np.random.default_rng(2)
    line = np.c_[np.linspace(0, 1, 30), rng.normal(scale=0.02, size=(30, 2))]
    obj = make_mesh_object("Line", line, edges=[(i, i + 1) for i in range(29)])
    select_only(obj)
    assert bpy.ops.object.hc_smooth(deviation_map=True, auto_amount=False, iterations=5) == {"FINISHED"}
    assert not np.array_equal(positions_of(obj.data), line.astype(np.float32))
    assert np.all(attribute_values(obj.data) == 0.0)
    assert np.all(colors_of(obj.data) == core.deviation_colors(np.zeros(1), 0.0, linear=True)[0])


# --- the modifier --------------------------------------------------------------------------------------------


def add_modifier(obj, **settings):
    select_only(obj)
    assert bpy.ops.object.hc_smooth_modifier_add(**settings) == {"FINISHED"}
    return obj.modifiers[-1]


def evaluated(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    return obj.evaluated_get(depsgraph).data


@pytest.mark.parametrize("method", ["HC", "LAPLACIAN"])
def test_modifier_outputs_the_move_along_the_normals(scene, method):
    obj = noisy_sphere(sigma=0.05)
    before, triangles = positions_of(obj.data), triangles_of(obj.data)
    add_modifier(obj, method=method, deviation_map=True, alpha=0.1, iterations=8)
    mesh = evaluated(obj)
    after = positions_of(mesh)
    assert not np.array_equal(after, before)
    expected = expected_deviation(before, after, triangles)
    np.testing.assert_allclose(attribute_values(mesh), expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    assert ATTRIBUTE not in attribute_names(obj.data)  # the original mesh stays as it is


def user_data_named_like_the_map(obj, kind):
    """Give ``obj`` a thing of the user's named hc_deviation: a UV map, an integer face attribute, a float point
    attribute or a vertex group (Geometry Nodes read each as an attribute of that name)."""
    mesh, rng = obj.data, np.random.default_rng(7)
    if kind == "uv map":
        mesh.uv_layers.new(name=ATTRIBUTE).data.foreach_set("uv", rng.random(2 * len(mesh.loops)).astype(np.float32))
    elif kind == "face integers":
        mesh.attributes.new(ATTRIBUTE, "INT", "FACE").data.foreach_set("value", np.arange(len(mesh.polygons)))
    elif kind == "point floats":
        mesh.attributes.new(ATTRIBUTE, "FLOAT", "POINT").data.foreach_set(
            "value", rng.random(len(mesh.vertices)).astype(np.float32)
        )
    else:
        obj.vertex_groups.new(name=ATTRIBUTE).add([0, 5, 9], 0.75, "REPLACE")


def users_data(obj, kind):
    """What ``obj``'s evaluated mesh holds under the map's name: the attribute's data, or the group's weights."""
    evaluated_object = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    if kind == "vertex group":
        return vertex_group_weights(evaluated_object, ATTRIBUTE)
    domain, data_type, values = attribute_data(evaluated_object.data, ATTRIBUTE)
    return domain, data_type, values.tolist()


@pytest.mark.parametrize("kind", ["uv map", "face integers", "point floats", "vertex group"])
def test_modifier_never_overwrites_what_the_user_named_like_the_map(scene, kind):
    """The modifier's map leaves a UV map, an attribute or a vertex group named hc_deviation as it is, and says
    in the Warnings panel why it stored no map (the operators choose another name; the modifier's output
    name is the one the user's materials read)."""
    obj = noisy_sphere(sigma=0.05)
    user_data_named_like_the_map(obj, kind)
    kept = users_data(obj, kind)
    modifier = add_modifier(obj, deviation_map=True, alpha=0.1, iterations=4)
    before = positions_of(obj.data)
    assert not np.array_equal(positions_of(evaluated(obj)), before)  # smoothed all the same
    assert users_data(obj, kind) == kept
    warnings = [w.message for w in modifier.node_warnings]
    assert any("Deviation Map not stored" in message and ATTRIBUTE in message for message in warnings), warnings
    # Without a thing of that name the map is stored and nothing is said.
    other = noisy_sphere(name="Other", sigma=0.05)
    modifier = add_modifier(other, deviation_map=True, alpha=0.1, iterations=4)
    assert ATTRIBUTE in attribute_names(evaluated(other))
    assert not [w.message for w in modifier.node_warnings if "Deviation Map" in w.message]


def test_modifier_off_adds_nothing(scene):
    obj = noisy_sphere(sigma=0.05)
    names = attribute_names(obj.data)
    modifier = add_modifier(obj)
    assert attribute_names(evaluated(obj)) == names
    inputs = __import__(ADDON + ".nodes.inputs", fromlist=["set_input"])
    inputs.set_input(modifier, "Deviation Map", True)
    assert ATTRIBUTE in attribute_names(evaluated(obj))


def test_modifier_passing_the_mesh_through_maps_zero(scene):
    # Zero iterations: the mesh comes out as it went in, and every deviation is 0.
    obj = noisy_grid()
    add_modifier(obj, deviation_map=True, iterations=0)
    assert np.all(attribute_values(evaluated(obj)) == 0.0)


# --- the command line -----------------------------------------------------------------------------------------


@pytest.fixture
def cli(addon):
    return __import__(ADDON + ".cli", fromlist=["main"])


def formats_module():
    return __import__(ADDON + ".cli.formats", fromlist=["parse"])


def write_scan(path, seed=0):
    """A noisy icosphere as a binary PLY with vertex colours (Blender's exporter)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere(sigma=0.05, seed=seed)
    obj.data.color_attributes.new("Col", "BYTE_COLOR", "POINT")
    select_only(obj)
    bpy.ops.wm.ply_export(filepath=str(path), export_selected_objects=True, export_uv=False, export_normals=False)
    return path


def vertex_values(data):
    """{property: values} of a PLY's vertex element, read with the command's own reader."""
    mesh = formats_module().parse(data, ".ply")
    return {prop.name: mesh._read(mesh.vertex, prop.name) for prop in mesh.vertex.properties}, mesh


def test_ply_result_holds_the_property(cli, capsys, tmp_path):
    source = write_scan(tmp_path / "scan.ply")
    assert cli.main([str(source), "-o", str(tmp_path / "plain"), "--iterations", "6"]) == 0
    assert cli.main([str(source), "-o", str(tmp_path / "map"), "--iterations", "6", "--deviation-attribute"]) == 0
    said = capsys.readouterr().out
    assert said.count("deviation map -") == 1  # the legend, under the file's progress line
    plain, plain_mesh = vertex_values((tmp_path / "plain" / "scan.ply").read_bytes())
    mapped, mesh = vertex_values((tmp_path / "map" / "scan.ply").read_bytes())
    deviation = mapped.pop(ATTRIBUTE)
    assert mapped.keys() == plain.keys() and {"red", "green", "blue"} <= set(plain)
    for name, values in plain.items():  # every other value as the run without the map wrote it
        np.testing.assert_array_equal(mapped[name], values, err_msg=name)
    np.testing.assert_array_equal(mesh.corners, plain_mesh.corners)
    before = formats_module().parse(source.read_bytes(), ".ply").positions.astype(np.float32)
    after = mesh.positions.astype(np.float32)
    triangles = mesh.corners.reshape(-1, 3)
    expected = expected_deviation(before, after, triangles)
    np.testing.assert_allclose(deviation, expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    extent = core.deviation_extent(deviation.astype(np.float32))
    assert f"deviation map -{extent:.3g} to +{extent:.3g}" in said


def test_obj_input_converted_to_ply_holds_it(cli, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    select_only(noisy_sphere(sigma=0.05))
    source = tmp_path / "scan.obj"
    bpy.ops.wm.obj_export(filepath=str(source), export_selected_objects=True, export_materials=False)
    argv = [str(source), "-o", str(tmp_path / "out"), "--format", "ply", "--deviation-attribute"]
    assert cli.main(argv) == 0
    values, _ = vertex_values((tmp_path / "out" / "scan.ply").read_bytes())
    assert ATTRIBUTE in values and np.abs(values[ATTRIBUTE]).max() > 0


@pytest.mark.parametrize("fmt", ["obj", "stl"])
def test_obj_and_stl_results_are_refused_before_any_work(cli, capsys, tmp_path, fmt):
    source = write_scan(tmp_path / "scan.ply")
    out = tmp_path / "out"
    capsys.readouterr()  # what the exporter said
    assert cli.main([str(source), "-o", str(out), "--format", fmt, "--deviation-attribute"]) == 2
    said = capsys.readouterr()
    assert "--deviation-attribute stores a value per vertex, which only PLY and .blend files hold" in said.err
    assert f"scan.{fmt}" in said.err and "--format ply" in said.err and said.out == ""
    assert not out.exists()
    plain_input = tmp_path / f"plain.{fmt}"
    plain_input.write_bytes(b"")  # never read: the refusal comes from the result's format
    assert cli.main([str(plain_input), "-o", str(out), "--deviation-attribute"]) == 2


def test_points_refuse_it(cli, capsys, tmp_path):
    source = write_scan(tmp_path / "scan.ply")
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--points", "--deviation-attribute"]) == 2
    assert "--deviation-attribute does not apply to point clouds" in capsys.readouterr().err


def test_blend_copy_holds_the_attributes(cli, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = noisy_sphere(name="Scan", sigma=0.05)
    before, triangles = positions_of(obj.data).copy(), triangles_of(obj.data)
    source = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--deviation-attribute"]) == 0
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "out" / "scene.blend"))
    check_map(bpy.data.objects["Scan"].data, before, triangles)
    bpy.ops.wm.open_mainfile(filepath=str(source))
    assert ATTRIBUTE not in attribute_names(bpy.data.objects["Scan"].data)  # the input stays as it was


def test_add_as_modifier_carries_the_option_and_says_what_differs(scene):
    draw = __import__(ADDON + ".operators.draw", fromlist=["modifier_differences"])
    spec = __import__(ADDON + ".settings_spec", fromlist=["MeshSettings"])
    assert "The modifier stores hc_deviation without its colours" in draw.modifier_differences(
        spec.MeshSettings(deviation_map=True)
    )
    assert not any("hc_deviation" in line for line in draw.modifier_differences(spec.MeshSettings()))
    obj = noisy_sphere(sigma=0.05)
    assert bpy.ops.object.hc_smooth(deviation_map=True, auto_amount=False) == {"FINISHED"}
    assert bpy.ops.object.hc_smooth_modifier_add(deviation_map=True, replace_smoothing=False) == {"FINISHED"}
    inputs = __import__(ADDON + ".nodes.inputs", fromlist=["get_input"])
    assert inputs.get_input(obj.modifiers[-1], "Deviation Map")
