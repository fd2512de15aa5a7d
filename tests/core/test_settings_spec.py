"""settings_spec: the one declaration of every setting, checked without Blender (it imports like core).

The Blender side (the properties built from it, and the command line's options) is checked in
tests/blender/test_ui.py and tests/blender/test_cli.py.
"""

import dataclasses
import itertools
import types

import pytest

import settings_spec as spec
from core.smoothing import METHODS as CORE_METHODS
from core.smoothing import MODES as CORE_MODES

SMALL_WORDS = {"a", "and", "in", "of", "per", "the", "to"}  # lower case inside a Title Case label
EVERY = [
    pytest.param(setting, id=f"{group}.{setting.name}")
    for group, settings in (("mesh", spec.MESH), ("points", spec.POINTS))
    for setting in settings
]


@pytest.mark.parametrize("settings", [spec.MESH, spec.POINTS], ids=["mesh", "points"])
def test_identifiers_and_flags_are_unique(settings):
    names = [setting.name for setting in settings]
    flags = [setting.flag for setting in settings if setting.flag]
    assert len(set(names)) == len(names) and len(set(flags)) == len(flags)
    assert all(name.isidentifier() and name.islower() for name in names)


def test_identifiers_users_rely_on():
    # Users' scripts, presets and the command line name these: they must not change.
    assert [s.name for s in spec.MESH] == [
        "method",
        "keep_sharp_edges",
        "sharpness_angle",
        "auto_amount",
        "keep_in_place",
        "alpha",
        "beta",
        "iterations",
        "mode",
        "tolerance",
        "max_deviation",
        "vertex_group",
        "invert_vertex_group",
        "pin_boundary",
        "keep_outline",
        "influence_group",
        "invert_influence_group",
        "output",
        "deviation_map",
    ]
    assert [s.name for s in spec.POINTS] == [
        "auto_amount",
        "alpha",
        "beta",
        "rounds",
        "iterations_per_round",
        "neighbours",
        "spacing_factor",
        "gap_factor",
        "min_quality",
        "swap",
        "vertex_group",
        "invert_vertex_group",
        "keep_rfs_mesh",
    ]
    assert spec.METHOD.identifiers == ("HC", "LAPLACIAN", "LAPLACIAN_CENTRAL", "LAPLACIAN_ORIGINAL")
    assert spec.MODE.identifiers == ("SIMULTANEOUS", "SEQUENTIAL")
    assert spec.OUTPUT.identifiers == ("MESH", "SHAPE_KEY")
    assert {s.flag: s.name for s in spec.MESH + spec.POINTS if s.flag} == {
        "method": "method",
        "keep-sharp-edges": "keep_sharp_edges",
        "sharpness-angle": "sharpness_angle",
        "alpha": "alpha",
        "beta": "beta",
        "iterations": "iterations",
        "mode": "mode",
        "tolerance": "tolerance",
        "max-deviation": "max_deviation",
        "fixed-group": "vertex_group",
        "invert-group": "invert_vertex_group",
        "pin-boundary": "pin_boundary",
        "keep-outline": "keep_outline",
        "slide": "keep_in_place",
        "influence-group": "influence_group",
        "invert-influence": "invert_influence_group",
        "deviation-attribute": "deviation_map",
        "rounds": "rounds",
        "steps-per-round": "iterations_per_round",
        "neighbours": "neighbours",
        "reach": "spacing_factor",
        "gap": "gap_factor",
    }


@pytest.mark.parametrize("setting", EVERY)
def test_default_has_the_kind_and_lies_within_the_limits(setting):
    assert type(setting.default) is spec.KINDS[setting.kind]
    for low, high in ((setting.min, setting.max), (setting.min, setting.soft_max)):
        assert low is None or setting.default >= low
        assert high is None or setting.default <= high
    if setting.kind == "enum":
        assert setting.default in setting.identifiers
    else:
        assert not setting.items
    if setting.kind not in ("float", "int"):
        assert (setting.min, setting.max, setting.soft_max, setting.step, setting.precision) == (None,) * 5
    if setting.kind == "int":
        assert (setting.step, setting.precision) == (None, None)


@pytest.mark.parametrize("setting", EVERY)
def test_texts_in_blenders_style(setting):
    # Tooltips are sentences without a final period; labels are Title Case (as Blender's);
    # command-line help is a phrase.
    texts = [setting.description] + [choice.description for choice in setting.items]
    for text in texts:
        assert text and text[0].isupper() and not text.endswith(".") and text == text.strip(), text
    for label in [setting.label] + [choice.label for choice in setting.items]:
        assert all(word[0].isupper() or word in SMALL_WORDS for word in label.split()), label
    if setting.flag:
        assert setting.help and not setting.help.endswith(".")
        assert setting.flag == setting.flag.lower() and "_" not in setting.flag
    else:
        assert setting.help is None and setting.metavar is None and setting.cli_default is None


def test_enum_items():
    for setting in (spec.METHOD, spec.MODE, spec.OUTPUT):
        identifiers = setting.identifiers
        assert len(set(identifiers)) == len(identifiers) and all(i.isupper() for i in identifiers)
    # The job code hands core the method's core name (and the mode in lower case): core must know them.
    assert [choice.core for choice in spec.METHOD.items] == list(CORE_METHODS)
    assert all(choice.short for choice in spec.METHOD.items)
    assert tuple(mode.lower() for mode in spec.MODE.identifiers) == CORE_MODES


def test_point_alpha_and_beta_differ_from_the_mesh_ones_only_where_declared():
    # Points smooth with a weaker pull and a beta nearer 0.5 (core.smooth_point_cloud); label, limits and
    # command-line option are the mesh settings' own.
    for mesh, point, changed in (
        # The panel rules: points have one method and no label that depends on it.
        (spec.ALPHA, spec.POINT_ALPHA, {"default", "step", "description", "cli_default", "active", "text"}),
        (spec.BETA, spec.POINT_BETA, {"default", "description", "active"}),
    ):
        differ = {f.name for f in dataclasses.fields(spec.Setting) if getattr(mesh, f.name) != getattr(point, f.name)}
        assert differ == changed
    assert (spec.POINT_ALPHA.default, spec.POINT_BETA.default) == (0.01, 0.55)


@pytest.mark.parametrize("settings", [spec.MESH, spec.POINTS], ids=["mesh", "points"])
def test_settings_class_holds_the_declared_defaults(settings):
    made = spec.settings_class("Made", settings, "A test.")
    values = made()
    assert [f.name for f in dataclasses.fields(made)] == [s.name for s in settings]
    assert all(getattr(values, s.name) == s.default for s in settings)
    # of() copies every field from anything that has them (an operator's properties).
    source = types.SimpleNamespace(**{s.name: s.default for s in settings}, extra="ignored")
    source.__dict__[settings[0].name] = "changed"
    copied = made.of(source)
    assert getattr(copied, settings[0].name) == "changed" and not hasattr(copied, "extra")


def test_mesh_parts_make_up_the_mesh_settings():
    # Every mesh setting is drawn with one part (N-panel: main, Fixed Vertices, after the convergence box).
    assert spec.MESH == spec.MESH_SMOOTHING + spec.MESH_VERTICES + spec.MESH_RESULT
    # The modifier holds mesh settings, three of them with its own limits and tooltips.
    mesh = {s.name: s for s in spec.MESH}
    assert {s.name for s in spec.MODIFIER} <= set(mesh)
    own = {s.name for s in spec.MODIFIER if s is not mesh[s.name]}
    assert own == {"iterations", "max_deviation", "deviation_map"}
    for setting in spec.MODIFIER:
        assert (setting.label, setting.kind, setting.default) == (
            mesh[setting.name].label,
            mesh[setting.name].kind,
            mesh[setting.name].default,
        )


@pytest.mark.parametrize("settings", [spec.MESH, spec.POINTS, spec.MODIFIER], ids=["mesh", "points", "modifier"])
def test_drawing_rules_read_only_the_settings_drawn_with_them(settings):
    # A panel hands the rules the values of the settings it draws ({name: value}); try every choice.
    names = {s.name for s in settings}
    choices = [(s.name, [c.identifier for c in s.items] if s.items else [s.default, not s.default]) for s in settings]
    for setting in settings:
        if setting.invert:  # a vertex group's Invert toggle is a bool of the same settings
            assert setting.kind == "string" and setting.invert in names
            assert next(s for s in settings if s.name == setting.invert).kind == "bool"
        for rule, kind in ((setting.active, bool), (setting.text, str)):
            if rule is None:
                continue
            for name, values in choices:
                for value in values:
                    state = {s.name: s.default for s in settings} | {name: value}
                    assert type(rule(state)) is kind, setting.name


def test_greyed_out_where_a_setting_does_not_apply():
    def active(setting, **values):
        return setting.active({s.name: s.default for s in spec.MESH} | values)

    assert not active(spec.ALPHA, method="LAPLACIAN", auto_amount=False)  # plain Laplacian has no alpha
    assert not active(spec.ALPHA, method="HC", auto_amount=True)  # chosen by the Automatic Amount
    assert active(spec.ALPHA, method="HC", auto_amount=False) and active(spec.ALPHA, method="LAPLACIAN_CENTRAL")
    assert active(spec.ITERATIONS, method="LAPLACIAN", auto_amount=True)  # the Automatic Amount is HC's only
    assert not active(spec.ITERATIONS, method="HC", auto_amount=True)
    assert not active(spec.BETA, method="LAPLACIAN_ORIGINAL") and not active(spec.MESH_AUTO_AMOUNT, method="LAPLACIAN")
    # The modifier has no Automatic Amount: Alpha and Iterations apply.
    modifier = {s.name: s.default for s in spec.MODIFIER}
    assert spec.ALPHA.active(modifier) and spec.ITERATIONS.active(modifier)
    assert spec.ALPHA.text(modifier | {"method": "LAPLACIAN_CENTRAL"}) == "Alpha (keep current)"


def test_alpha_or_iterations_given_switch_the_amount_off_in_every_rule():
    """What the caller set (a script, an F9 edit, a command line's options) is read by one rule: Alpha or
    Iterations (points: Steps per Round) given run every number as set, and the panels draw them live."""
    mesh = {s.name: s.default for s in spec.MESH}
    points = {s.name: s.default for s in spec.POINTS}
    assert spec.automatic(mesh) and spec.automatic(points)
    assert spec.automatic(mesh, {"beta", "max_deviation"})  # chosen unless given, and the rest still is
    for values, switches, greyed in (
        (mesh, ("alpha", "iterations"), (spec.ALPHA, spec.ITERATIONS)),
        (points, ("alpha", "iterations_per_round"), (spec.POINT_ALPHA, spec.ITERATIONS_PER_ROUND)),
    ):
        for name in switches:
            assert not spec.automatic(values, {name})
            for setting in greyed:
                assert not setting.active(values) and setting.active(values, {name}), (setting.name, name)
    assert spec.KEEP_IN_PLACE.active(mesh) and not spec.KEEP_IN_PLACE.active(mesh, {"iterations"})
    assert spec.chosen(mesh) == set(spec.CHOSEN)
    assert spec.chosen(mesh, {"beta"}) == set(spec.CHOSEN) - {"beta"}
    assert spec.chosen(mesh, {"alpha"}) == set() and spec.chosen(mesh | {"auto_amount": False}) == set()


@pytest.mark.parametrize("method", [choice.identifier for choice in spec.METHOD.items])
def test_a_panel_button_passes_what_its_panel_draws_live_and_nothing_greyed(method):
    """The N-panel's button (ui/settings.copy_to) hands over every setting but those the Automatic Amount
    chooses and the user left alone; Alpha and Iterations, greyed out while it runs, never (only its
    checkbox switches it off), so the run is what the panel shows."""
    for keep_sharp_edges, auto_amount in itertools.product((False, True), repeat=2):
        values = {s.name: s.default for s in spec.MESH} | {
            "method": method,
            "keep_sharp_edges": keep_sharp_edges,
            "auto_amount": auto_amount,
        }
        for changed in itertools.chain.from_iterable(
            itertools.combinations(spec.CHOSEN, k) for k in range(len(spec.CHOSEN) + 1)
        ):
            passed = set(spec.passed_by_panel(values, changed))
            assert passed <= {s.name for s in spec.MESH}
            # The operator, given what was passed, runs the Automatic Amount exactly when the panel shows it.
            assert spec.automatic(values, passed & set(spec.CHOSEN)) is spec.automatic(values)
            for name in spec.CHOSEN:
                expected = not spec.automatic(values) or (name in changed and name not in ("alpha", "iterations"))
                assert (name in passed) is expected, (values, changed, name)


def test_plain_settings_objects_hold_the_declarations():
    for made, settings in ((spec.MeshSettings, spec.MESH), (spec.PointSettings, spec.POINTS)):
        assert [f.name for f in dataclasses.fields(made)] == [s.name for s in settings]


def test_every_core_argument_is_an_argument_of_the_mesh_pipeline():
    """A setting's ``argument`` is a parameter of core.MeshSmoother; the settings the Automatic Amount
    chooses are those MeshSmoother takes as "auto"; every enum item names its core value."""
    import inspect

    import core

    parameters = inspect.signature(core.MeshSmoother).parameters
    arguments = [s for s in spec.MESH if s.argument]
    assert {s.argument for s in arguments} >= {"method", "alpha", "beta", "iterations", "mode", "tolerance"}
    for setting in arguments:
        assert setting.argument in parameters, setting.name
        # Keep in Place is "auto" in core as well: the add-on's checkbox, on, passes that (jobs/mesh.py).
        automatic = setting.chosen or setting is spec.KEEP_IN_PLACE
        assert (parameters[setting.argument].default == core.AUTO) == automatic, setting.name
        for choice in setting.items:
            assert choice.core, (setting.name, choice.identifier)


def test_keep_sharp_edges_defaults_are_cores():
    """The add-on's Sharpness starts where core's does (settings_spec cannot import core)."""
    from core.mesh import sharp_edges

    assert spec.SHARPNESS_ANGLE.default == sharp_edges.DEFAULT_SHARPNESS_ANGLE
    assert spec.KEEP_SHARP_EDGES.default is False
    values = {s.name: s.default for s in spec.MESH}
    assert spec.automatic(values) and spec.automatic({**values, "method": "LAPLACIAN", "keep_sharp_edges": True})
    assert not spec.automatic({**values, "method": "LAPLACIAN"})


def test_one_rule_for_the_automatic_amount():
    """Alpha or Iterations given switch it off, Beta and the Deviation Limit do not; the modifier's settings
    (no auto_amount) have none; a caller that leaves out a setting the rule reads fails loudly."""
    values = {s.name: s.default for s in spec.MESH}
    assert not spec.automatic(values, given={"alpha"}) and not spec.automatic(values, given={"iterations"})
    assert spec.automatic(values, given={"beta", "max_deviation"})
    assert not spec.automatic({s.name: s.default for s in spec.MODIFIER})
    with pytest.raises(KeyError):
        spec.automatic({"method": "LAPLACIAN", "auto_amount": True})
