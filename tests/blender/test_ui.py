"""The ui/ package: scene settings, panel, menu entries, presets, fixed-vertex count (headless bpy).

Panels cannot be drawn without a window, so draw() runs against a recording layout: it sees the
same calls (prop, operator, label) Blender would make, and the test inspects them.
"""

import ast
import importlib
import os
import types

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, noisy_grid, noisy_sphere, positions_of, select_only

import core
from core.convergence import convergence_lines

OPERATORS = ("object.hc_smooth", "mesh.hc_smooth")


def ui_module(name=""):
    return importlib.import_module(f"{ADDON}.ui{name}")


def shipped_preset_files():
    """The preset files inside the installed extension."""
    preset = ui_module(".preset")
    folder = os.path.join(preset.PRESET_ROOT, "presets", preset.PRESET_SUBDIR)
    return sorted(os.path.join(folder, name) for name in os.listdir(folder) if name.endswith(".py"))


class RecordingLayout:
    """Stands in for bpy.types.UILayout: records every call; sub-layouts share the record."""

    def __init__(self, record=None, shown=None):
        self.record = [] if record is None else record
        self.shown = {} if shown is None else shown  # {property name: drawn live (not greyed out)}
        self.active = True
        self.enabled = True
        self.alert = False
        self.use_property_split = False
        self.use_property_decorate = True
        self.operator_context = "INVOKE_DEFAULT"

    def _sub(self, *args, **kwargs):
        sub = RecordingLayout(self.record, self.shown)
        sub.active = self.active  # greyed out with its parent, as Blender draws it
        return sub

    row = column = box = split = _sub

    def operator(self, idname, **kwargs):
        properties = types.SimpleNamespace()
        self.record.append(("operator", idname, kwargs, properties))
        return properties

    def __getattr__(self, name):  # prop, prop_search, label, menu, separator, ...
        def call(*args, **kwargs):
            self.record.append((name, args, kwargs))
            if name in ("prop", "prop_search"):
                self.shown[args[1]] = self.active

        return call

    def calls(self, kind):
        return [entry for entry in self.record if entry[0] == kind]

    def labels(self):
        return [kwargs.get("text", "") for _, _, kwargs in self.calls("label")]

    def buttons(self):
        return [(idname, properties) for _, idname, _, properties in self.calls("operator")]


def draw(panel_class, context):
    layout = RecordingLayout()
    panel_class.draw(types.SimpleNamespace(layout=layout), context)
    return layout


def redo_panel(operator):
    """Draw a registered operator's redo panel into a RecordingLayout (an operator's layout is read-only: a
    stand-in of its class name carries its values and its properties, which tell what the caller set)."""
    properties = operator.properties
    names = [prop.identifier for prop in properties.bl_rna.properties if prop.identifier != "rna_type"]
    operator_class = getattr(bpy.types, operator.bl_idname)
    stand_in = type("StandIn", (), {"bl_idname": operator_class.bl_idname})()
    stand_in.__dict__.update({name: getattr(properties, name) for name in names}, layout=RecordingLayout())
    stand_in.properties = properties
    operator_class.draw(stand_in, bpy.context)
    return stand_in.layout


KINDS = {"ENUM": "enum", "FLOAT": "float", "INT": "int", "BOOLEAN": "bool", "STRING": "string"}


def assert_built_from(prop, setting):
    """An RNA property says what its declaration says: texts, kind, default, limits, items."""
    assert (prop.identifier, prop.name, prop.description) == (setting.name, setting.label, setting.description)
    assert KINDS[prop.type] == setting.kind, setting.name
    if setting.kind == "float":  # single precision in Blender: equal once the declaration is rounded as well
        assert prop.default == np.float32(setting.default), setting.name
    else:
        assert prop.default == setting.default, setting.name
    limits = {"min": "hard_min", "max": "hard_max", "soft_max": "soft_max", "step": "step", "precision": "precision"}
    for key, rna_key in limits.items():
        if getattr(setting, key) is not None:
            assert getattr(prop, rna_key) == np.float32(getattr(setting, key)), (setting.name, key)
    assert [(item.identifier, item.name, item.description) for item in getattr(prop, "enum_items", ())] == [
        (choice.identifier, choice.label, choice.description) for choice in setting.items
    ]


@pytest.fixture
def settings(scene):
    return scene.hc_smooth


# --- registration ---------------------------------------------------------------------------------------


def test_scene_settings_and_operators_are_built_from_the_declarations(settings):
    spec = importlib.import_module(f"{ADDON}.settings_spec")
    routes = {
        "scene.hc_smooth": (settings.bl_rna.properties, spec.MESH),
        "object.hc_smooth": (bpy.ops.object.hc_smooth.get_rna_type().properties, spec.MESH),
        "mesh.hc_smooth": (bpy.ops.mesh.hc_smooth.get_rna_type().properties, spec.MESH),
        "object.hc_smooth_points": (bpy.ops.object.hc_smooth_points.get_rna_type().properties, spec.POINTS),
    }
    inherited = {"rna_type", "name"}  # every struct's, and every PropertyGroup's
    for route, (properties, declared) in routes.items():
        assert {prop.identifier for prop in properties} - inherited == {s.name for s in declared}, route
        for setting in declared:
            assert_built_from(properties[setting.name], setting)
    # A button copies every scene setting onto the operator, and presets store some of them.
    scene_settings = ui_module(".settings")
    assert scene_settings.OPERATOR_SETTINGS == tuple(s.name for s in spec.MESH)
    assert set(scene_settings.PRESET_SETTINGS) < set(scene_settings.OPERATOR_SETTINGS)


def test_panel_menu_entries_and_preset_path_registered(addon):
    assert bpy.types.VIEW3D_PT_hc_smooth.bl_category == "HC Smooth"
    assert bpy.types.VIEW3D_PT_hc_smooth.bl_region_type == "UI"
    assert bpy.types.VIEW3D_PT_hc_smooth_fixed.bl_parent_id == "VIEW3D_PT_hc_smooth"
    panel = ui_module(".panel")
    for menu, entry in panel.MENU_ENTRIES:
        assert entry in menu._dyn_ui_initialize()
    preset = ui_module(".preset")
    assert os.path.join(preset.PRESET_ROOT, "presets", "hc_smooth") in bpy.utils.preset_paths("hc_smooth")


def test_disable_removes_everything_enable_restores(addon):
    panel, preset, fixed = ui_module(".panel"), ui_module(".preset"), ui_module(".fixed")
    entries = [(menu, entry) for menu, entry in panel.MENU_ENTRIES]
    preset_dir = os.path.join(preset.PRESET_ROOT, "presets", "hc_smooth")
    bpy.ops.preferences.addon_disable(module=ADDON)
    try:
        for name in (
            "VIEW3D_PT_hc_smooth",
            "VIEW3D_PT_hc_smooth_fixed",
            "HC_SMOOTH_MT_presets",
            "HC_SMOOTH_OT_preset_add",
            "HC_SMOOTH_OT_count_fixed",
            "HCSmoothSettings",
        ):
            assert not hasattr(bpy.types, name), name
        assert not hasattr(bpy.types.Scene, "hc_smooth")
        for menu, entry in entries:
            assert entry not in menu._dyn_ui_initialize()
        assert preset_dir not in bpy.utils.preset_paths("hc_smooth")
        assert fixed._on_depsgraph_update not in bpy.app.handlers.depsgraph_update_post
    finally:
        bpy.ops.preferences.addon_enable(module=ADDON)
    assert hasattr(bpy.types.Scene, "hc_smooth")
    assert preset_dir in bpy.utils.preset_paths("hc_smooth")


# --- the panel ------------------------------------------------------------------------------------------


def test_panel_polls_in_object_and_edit_mode_only(scene):
    obj = noisy_sphere()
    panel = bpy.types.VIEW3D_PT_hc_smooth
    assert panel.poll(bpy.context)
    bpy.ops.object.mode_set(mode="EDIT")
    assert panel.poll(bpy.context)
    bpy.ops.object.mode_set(mode="SCULPT")
    assert not panel.poll(bpy.context)
    bpy.ops.object.mode_set(mode="OBJECT")
    assert obj.mode == "OBJECT"


@pytest.mark.parametrize("mode, idname", [("OBJECT", "object.hc_smooth"), ("EDIT", "mesh.hc_smooth")])
def test_smooth_button_carries_the_scene_settings(settings, mode, idname):
    noisy_sphere()
    bpy.ops.object.mode_set(mode=mode)
    settings.method, settings.alpha, settings.beta = "LAPLACIAN_ORIGINAL", 0.3, 0.8
    settings.iterations, settings.mode, settings.tolerance = 17, "SEQUENTIAL", 0.002
    settings.invert_vertex_group, settings.pin_boundary, settings.output = True, True, "SHAPE_KEY"
    layout = draw(bpy.types.VIEW3D_PT_hc_smooth, bpy.context)
    ((button, properties),) = [(name, props) for name, props in layout.buttons() if name in OPERATORS]
    assert button == idname
    for name in ui_module(".settings").OPERATOR_SETTINGS:
        assert getattr(properties, name) == getattr(settings, name), name
    bpy.ops.object.mode_set(mode="OBJECT")


def test_button_settings_run_the_operator_like_the_core(settings):
    """What the button hands over is a complete, valid set of operator arguments."""
    obj = noisy_sphere(subdivisions=2)
    before = positions_of(obj.data)
    settings.auto_amount, settings.alpha, settings.beta, settings.iterations = False, 0.2, 0.7, 4
    layout = draw(bpy.types.VIEW3D_PT_hc_smooth, bpy.context)
    ((_, properties),) = [button for button in layout.buttons() if button[0] == "object.hc_smooth"]
    assert bpy.ops.object.hc_smooth(**vars(properties)) == {"FINISHED"}
    edges = np.array([tuple(e.vertices) for e in obj.data.edges])
    expected = core.hc_smooth(before, edges, alpha=settings.alpha, beta=settings.beta, iterations=4)
    assert np.array_equal(positions_of(obj.data), expected)


@pytest.mark.parametrize("alpha, beta", [(0.1, 0.6), (0.0, 0.6), (0.1, 0.5), (0.3, 0.2), (0.0, 0.0)])
def test_panel_shows_the_convergence_region(settings, alpha, beta):
    settings.method, settings.alpha, settings.beta, settings.auto_amount = "HC", alpha, beta, False
    layout = draw(bpy.types.VIEW3D_PT_hc_smooth, bpy.context)
    icons = [kwargs.get("icon") for _, _, kwargs in layout.calls("label")]
    inside = core.in_convergence_region(settings.alpha, settings.beta)
    assert ("CHECKMARK" in icons) == inside and ("ERROR" in icons) == (not inside)
    # The automatic amount sets alpha itself (and stops in time): only beta decides.
    settings.auto_amount = True
    icons = [kwargs.get("icon") for _, _, kwargs in draw(bpy.types.VIEW3D_PT_hc_smooth, bpy.context).calls("label")]
    assert ("CHECKMARK" in icons) == (settings.beta > 0.5)


def test_panel_draws_every_mesh_setting_once(settings):
    # The main panel draws how strongly to smooth and the output, the Fixed Vertices subpanel the rest.
    spec = importlib.import_module(f"{ADDON}.settings_spec")
    noisy_sphere()
    drawn = []
    for panel in (bpy.types.VIEW3D_PT_hc_smooth, bpy.types.VIEW3D_PT_hc_smooth_fixed):
        layout = draw(panel, bpy.context)
        drawn += [
            args[1] for kind in ("prop", "prop_search") for _, args, _ in layout.calls(kind) if args[0] == settings
        ]
    assert sorted(drawn) == sorted(s.name for s in spec.MESH)


# --- fixed vertices -------------------------------------------------------------------------------------


def fixed_count_label(context):
    layout = draw(bpy.types.VIEW3D_PT_hc_smooth_fixed, context)
    return [text for text in layout.labels() if text.startswith("Fixed:")], layout


def grid_boundary_count(obj):
    """Vertices on the rim of a noisy_grid (noise is in z only; the grid spans [-1, 1]²)."""
    xy = positions_of(obj.data)[:, :2]
    return int(np.count_nonzero(np.isclose(np.abs(xy), 1.0, atol=1e-5).any(axis=1)))


def test_fixed_count_matches_group_and_boundary(settings):
    obj = noisy_grid(size=10)
    n = len(obj.data.vertices)
    boundary = grid_boundary_count(obj)
    members = [0, 11, 12, 33, 47, 55]  # some on the boundary (0), most inside
    obj.vertex_groups.new(name="Keep").add(members, 1.0, "REPLACE")
    texts = ui_module(".texts")

    settings.pin_boundary = True
    assert fixed_count_label(bpy.context)[0] == [texts.count_line(boundary, n)]
    settings.pin_boundary, settings.vertex_group = False, "Keep"
    assert fixed_count_label(bpy.context)[0] == [texts.count_line(len(members), n)]
    settings.invert_vertex_group = True
    assert fixed_count_label(bpy.context)[0] == [texts.count_line(n - len(members), n)]
    settings.vertex_group = "Missing"
    labels, layout = fixed_count_label(bpy.context)
    assert not labels and any("Missing" in text for text in layout.labels())


def test_fixed_count_follows_geometry_changes(settings):
    obj = noisy_grid(size=6)
    settings.pin_boundary = True
    before, _ = fixed_count_label(bpy.context)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.subdivide()  # more boundary vertices
    bpy.ops.object.mode_set(mode="OBJECT")
    after, _ = fixed_count_label(bpy.context)
    n = len(obj.data.vertices)
    assert after == [ui_module(".texts").count_line(grid_boundary_count(obj), n)] and after != before


def test_large_meshes_are_counted_on_request(settings, monkeypatch):
    fixed = ui_module(".fixed")
    monkeypatch.setattr(fixed, "AUTO_COUNT_LIMIT", 10)
    obj = noisy_grid(size=6)
    settings.pin_boundary = True
    labels, layout = fixed_count_label(bpy.context)
    assert not labels and ("hc_smooth.count_fixed",) == tuple(name for name, _ in layout.buttons())
    assert bpy.ops.hc_smooth.count_fixed() == {"FINISHED"}
    labels, _ = fixed_count_label(bpy.context)
    assert labels == [ui_module(".texts").count_line(grid_boundary_count(obj), len(obj.data.vertices))]


def test_edit_mode_counts_unselected_vertices(settings):
    obj = noisy_sphere(subdivisions=2)
    n = len(obj.data.vertices)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    bpy.ops.object.mode_set(mode="OBJECT")
    for index in range(0, n, 3):
        obj.data.vertices[index].select = True
    selected = len(range(0, n, 3))
    bpy.ops.object.mode_set(mode="EDIT")
    texts = ui_module(".texts")
    labels, _ = fixed_count_label(bpy.context)
    assert labels == [texts.edit_count_line(selected, n, more_rules=False)]
    assert labels == [f"Fixed: {n - selected:,} of {n:,} vertices"]
    bpy.ops.object.mode_set(mode="OBJECT")


# --- menus ----------------------------------------------------------------------------------------------


def test_menu_entries_call_the_operator_of_the_mode(settings):
    noisy_sphere()
    panel = ui_module(".panel")
    settings.auto_amount, settings.iterations = False, 23
    layout = RecordingLayout()
    panel.draw_object_menu_entry(types.SimpleNamespace(layout=layout), bpy.context)
    ((idname, properties),) = layout.buttons()
    assert idname == "object.hc_smooth" and properties.iterations == 23
    bpy.ops.object.mode_set(mode="EDIT")
    layout = RecordingLayout()
    panel.draw_edit_menu_entry(types.SimpleNamespace(layout=layout), bpy.context)
    ((idname, properties),) = layout.buttons()
    assert idname == "mesh.hc_smooth" and properties.iterations == 23
    bpy.ops.object.mode_set(mode="OBJECT")


def test_buttons_leave_the_automatic_amount_its_numbers(settings):
    """With the Automatic Amount on, a button passes neither Alpha nor Iterations (the operator would take
    them as given and run them), and Beta only once the user changed it."""
    noisy_sphere()
    panel = ui_module(".panel")
    settings.iterations, settings.alpha = 23, 0.3  # greyed out while the Automatic Amount is on

    def button():
        layout = RecordingLayout()
        panel.draw_object_menu_entry(types.SimpleNamespace(layout=layout), bpy.context)
        ((_, properties),) = layout.buttons()
        return vars(properties)

    passed = button()
    assert passed["auto_amount"] is True and not {"alpha", "iterations", "beta"} & set(passed)
    settings.beta = 0.7
    passed = button()
    assert passed["beta"] == pytest.approx(0.7) and not {"alpha", "iterations"} & set(passed)


@pytest.mark.parametrize("method", ["LAPLACIAN", "LAPLACIAN_CENTRAL", "LAPLACIAN_ORIGINAL"])
def test_keep_sharp_edges_button_runs_its_automatic_amount_with_any_method(settings, capfd, method):
    """Keep Sharp Edges has its own Automatic Amount whatever the method: the panel greys Alpha and Iterations
    out, and the button passes none of the numbers it chooses, so the run is the Automatic Amount's."""
    spec = importlib.import_module(f"{ADDON}.settings_spec")
    noisy_sphere(subdivisions=2)
    settings.method, settings.keep_sharp_edges, settings.auto_amount = method, True, True
    values = {setting.name: getattr(settings, setting.name) for setting in spec.MESH}
    assert not spec.ALPHA.active(values) and not spec.ITERATIONS.active(values)  # greyed out
    layout = draw(bpy.types.VIEW3D_PT_hc_smooth, bpy.context)
    ((_, properties),) = [button for button in layout.buttons() if button[0] == "object.hc_smooth"]
    passed = vars(properties)
    assert passed["keep_sharp_edges"] is True and passed["auto_amount"] is True
    assert not {"alpha", "beta", "iterations", "max_deviation"} & set(passed)
    capfd.readouterr()
    assert bpy.ops.object.hc_smooth(**passed) == {"FINISHED"}
    assert "automatic amount" in capfd.readouterr().out


@pytest.mark.parametrize("given", [{"alpha": 0.0}, {"iterations": 3}, {"alpha": 0.0, "iterations": 3}])
def test_redo_panel_draws_live_the_numbers_the_caller_set(scene, capfd, given):
    """Alpha or Iterations set by the caller (a script, or an edit in the F9 panel) run every number as set,
    the Automatic Amount's checkbox notwithstanding: the redo panel draws them live, warns about the alpha
    that ran (0 leaves HC's convergence region) and does not say the modifier would take them otherwise."""
    select_only(noisy_sphere(subdivisions=2))
    bpy.ops.ed.undo_push(message="Before")
    capfd.readouterr()
    assert bpy.ops.object.hc_smooth("INVOKE_DEFAULT", True, **given) == {"FINISHED"}
    ran = capfd.readouterr().out
    assert "automatic amount" not in ran  # every number as set
    operator = bpy.context.window_manager.operators[-1]
    assert operator.properties.auto_amount is True
    panel = redo_panel(operator)
    assert panel.shown["alpha"] and panel.shown["iterations"] and panel.shown["auto_amount"]
    assert "The modifier takes Alpha, Iterations and Deviation Limit as set" not in panel.labels()
    if "alpha" in given:
        assert "Outside the convergence region:" in panel.labels() and "alpha is 0" in ran
    # Left to the Automatic Amount, they are greyed out: it chooses them (called as a click is, the run
    # brings the last run's values back, and they are not the caller's).
    bpy.ops.ed.undo_push(message="Again")
    assert bpy.ops.object.hc_smooth("INVOKE_DEFAULT", True) == {"FINISHED"}
    panel = redo_panel(bpy.context.window_manager.operators[-1])
    assert not panel.shown["alpha"] and not panel.shown["iterations"]
    assert "automatic amount" in capfd.readouterr().out


def test_points_redo_panel_draws_live_the_numbers_the_caller_set(scene):
    """The point-cloud operator runs Alpha or Steps per Round as set when the caller sets either: its redo
    panel draws both live then, and greys them out when the Automatic Amount chooses them."""
    directions = np.random.default_rng(0).normal(size=(800, 3))
    mesh = bpy.data.meshes.new("Scan")
    mesh.from_pydata((directions / np.linalg.norm(directions, axis=1)[:, None]).tolist(), [], [])
    obj = bpy.data.objects.new("Scan", mesh)
    bpy.context.scene.collection.objects.link(obj)
    select_only(obj)
    for given, live in (({"alpha": 0.05}, True), ({"iterations_per_round": 4}, True), ({}, False)):
        bpy.ops.ed.undo_push(message="Before")
        assert bpy.ops.object.hc_smooth_points("INVOKE_DEFAULT", True, rounds=1, **given) == {"FINISHED"}
        operator = bpy.context.window_manager.operators[-1]
        assert operator.bl_idname == "OBJECT_OT_hc_smooth_points" and operator.properties.auto_amount is True
        panel = redo_panel(operator)
        assert panel.shown["alpha"] is live and panel.shown["iterations_per_round"] is live, given


# --- presets --------------------------------------------------------------------------------------------


def preset_assignments(path):
    """{name: value} of the `settings.name = value` lines of a preset file."""
    values = {}
    for node in ast.parse(open(path, encoding="utf-8").read()).body:
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Attribute):
            values[node.targets[0].attr] = ast.literal_eval(node.value)
    return values


def apply_preset(path):
    return bpy.ops.script.execute_preset(filepath=path, menu_idname="HC_SMOOTH_MT_presets")


def test_shipped_presets_apply_their_values(settings):
    files = shipped_preset_files()
    names = {os.path.basename(path) for path in files}
    assert {"Light_scan_noise.py", "Heavy_scan_noise.py"} <= names
    preset_settings = set(ui_module(".settings").PRESET_SETTINGS)
    for path in files:
        values = preset_assignments(path)
        assert set(values) == preset_settings, path
        assert core.in_convergence_region(values["alpha"], values["beta"]), path
        settings.vertex_group, settings.output = "Untouched", "SHAPE_KEY"
        assert apply_preset(path) == {"FINISHED"}
        for name, value in values.items():
            expected = pytest.approx(value, rel=1e-6) if isinstance(value, float) else value
            assert getattr(settings, name) == expected, (path, name)
        assert (settings.vertex_group, settings.output) == ("Untouched", "SHAPE_KEY")
        assert bpy.types.HC_SMOOTH_MT_presets.bl_label == bpy.path.display_name(
            os.path.splitext(os.path.basename(path))[0], title_case=False
        )


def test_presets_are_ordered_by_noise_strength():
    """Heavier noise: more iterations and a weaker pull to the (noisy) original points."""
    by_name = {os.path.basename(p): preset_assignments(p) for p in shipped_preset_files()}
    light, heavy = by_name["Light_scan_noise.py"], by_name["Heavy_scan_noise.py"]
    assert heavy["iterations"] > light["iterations"] and heavy["alpha"] < light["alpha"]


def test_add_apply_and_remove_a_user_preset(settings):
    settings.alpha, settings.beta, settings.iterations, settings.mode = 0.25, 0.75, 33, "SEQUENTIAL"
    assert bpy.ops.hc_smooth.preset_add(name="My Scanner") == {"FINISHED"}
    path = bpy.utils.preset_find("My_Scanner", "hc_smooth")
    assert path and os.path.exists(path)
    assert os.path.dirname(path) == bpy.utils.user_resource("SCRIPTS", path=os.path.join("presets", "hc_smooth"))
    settings.alpha, settings.beta, settings.iterations, settings.mode = 0.1, 0.6, 10, "SIMULTANEOUS"
    assert apply_preset(path) == {"FINISHED"}
    assert (settings.alpha, settings.beta, settings.iterations, settings.mode) == (
        pytest.approx(0.25),
        pytest.approx(0.75),
        33,
        "SEQUENTIAL",
    )
    assert bpy.ops.hc_smooth.preset_add(name="My_Scanner", remove_name=True) == {"FINISHED"}
    assert not os.path.exists(path)


def test_shipped_presets_cannot_be_removed(settings):
    path = shipped_preset_files()[0]
    name = os.path.splitext(os.path.basename(path))[0]
    assert bpy.ops.hc_smooth.preset_add(name=name, remove_name=True) == {"CANCELLED"}
    assert os.path.exists(path)


def test_fixed_count_is_recounted_after_a_geometry_update(settings):
    obj = noisy_grid(size=6)
    group = obj.vertex_groups.new(name="Keep")
    group.add([3, 4, 5], 1.0, "REPLACE")
    settings.vertex_group = "Keep"
    n = len(obj.data.vertices)
    texts = ui_module(".texts")
    assert fixed_count_label(bpy.context)[0] == [texts.count_line(3, n)]
    group.remove([4])  # same mesh, same vertex count: only Blender's update notice tells the cache
    obj.data.update()
    bpy.context.view_layer.update()
    assert fixed_count_label(bpy.context)[0] == [texts.count_line(2, n)]


def redo_stand_in(idname, **values):
    """What an operator's draw() reads, without a running operator (whose layout is read-only): its settings as
    the operator snapshots them, its idname, and a RecordingLayout."""
    spec = importlib.import_module(f"{ADDON}.settings_spec")
    props = (spec.PointSettings if "points" in idname else spec.MeshSettings)(**values)
    props.bl_idname, props.layout = getattr(bpy.types, idname).bl_idname, RecordingLayout()
    return props


@pytest.mark.parametrize("idname", ["OBJECT_OT_hc_smooth", "OBJECT_OT_hc_smooth_points"])
def test_redo_panels_draw_the_fixed_group_and_the_convergence_warning(scene, idname):
    # The operators' draw() (the F9 panel) shares its fixed-group row and convergence label.
    obj = noisy_sphere()
    operator_class = getattr(bpy.types, idname)
    props = redo_stand_in(idname, alpha=0.1, beta=0.6, auto_amount=False)
    operator_class.draw(props, bpy.context)
    searched = [args for args, _ in ((e[1], e[2]) for e in props.layout.calls("prop_search"))]
    assert searched and searched[0][1:3] == ("vertex_group", obj)
    if idname != "OBJECT_OT_hc_smooth_points":  # the mesh operators: the painted influence too
        assert [args[1:3] for args in searched[1:]] == [("influence_group", obj)]
    assert [e[1][1] for e in props.layout.calls("prop")].count("invert_vertex_group") == 1
    assert not props.layout.labels()  # inside the region: no warning
    props.layout, props.beta = RecordingLayout(), 0.4
    operator_class.draw(props, bpy.context)
    # The N-panel's lines (core's, one helper), for the smallest alpha the run can use.
    alpha = (
        importlib.import_module(f"{ADDON}.operators.point_cloud").lowest_alpha(props)
        if "points" in idname
        else props.alpha
    )
    _, lines = convergence_lines("hc", alpha, 0.4)
    assert props.layout.labels() == lines and "Outside the convergence region:" in lines
