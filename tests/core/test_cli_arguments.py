"""The command line's parsing and planning (cli/arguments.py), without Blender: `cli` imports no bpy.

The repository root is loaded as the package ``hc_smooth`` without running its ``__init__`` (which
registers Blender classes), as Blender loads it, so cli/arguments' relative imports resolve.
"""

import importlib
import importlib.machinery
import importlib.util
import math
import os
import subprocess
import sys

import pytest
from conftest import ROOT

PACKAGE = "hc_smooth"


def load(name):
    """``hc_smooth.<name>`` from this repository, the package itself left unexecuted."""
    if PACKAGE not in sys.modules:
        package = importlib.util.module_from_spec(importlib.machinery.ModuleSpec(PACKAGE, None, is_package=True))
        package.__path__ = [str(ROOT)]
        sys.modules[PACKAGE] = package
    return importlib.import_module(f"{PACKAGE}.{name}")


arguments = load("cli.arguments")
spec = load("settings_spec")


def test_cli_package_imports_no_blender_module():
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]); import test_cli_arguments as t; "
        "t.load('cli'); t.load('cli.arguments'); t.load('console_capture'); "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('bpy', 'mathutils', '_bpy')))"
    )
    here = os.path.dirname(__file__)
    completed = subprocess.run(
        [sys.executable, "-c", code, here], capture_output=True, text=True, cwd=here, check=True, timeout=60
    )
    assert completed.stdout.strip() == "[]"


@pytest.mark.parametrize(
    "argv, message",
    [
        (["a.ply"], "either -o OUTDIR or --in-place"),
        (["a.ply", "-o", "out", "--in-place"], "either -o OUTDIR or --in-place"),
        (["a.ply", "-o", "out", "--alpha", "1.5"], "outside [0, 1]"),
        (["a.ply", "-o", "out", "--iterations", "-1"], "negative"),
        (["a.ply", "-o", "out", "--invert-group"], "--invert-group needs --fixed-group"),
        (["a.ply", "-o", "out", "--invert-influence"], "--invert-influence needs --influence-group"),
        (["a.ply", "-o", "out", "--sharpness-angle", "45"], "--sharpness-angle needs --keep-sharp-edges"),
        (
            ["a.ply", "-o", "out", "--iterations", "100000000000"],
            "--iterations 100000000000 is above 1000, the most the command line runs (as the HC Smooth modifier): "
            "it runs unattended",
        ),
        # Point clouds: rounds times steps per round are HC steps too, with the same maximum.
        (
            ["a.ply", "-o", "out", "--points", "--rounds", "100000000000"],
            "--rounds 100000000000 (at least one step each) makes 100000000000 HC steps, above 1000, the most "
            "the command line runs",
        ),
        (
            ["a.ply", "-o", "out", "--points", "--steps-per-round", "100000000"],
            "--steps-per-round 100000000 with the default 3 rounds makes 300000000 HC steps, above 1000",
        ),
        (
            ["a.ply", "-o", "out", "--points", "--rounds", "40", "--steps-per-round", "30"],
            "--steps-per-round 30 with --rounds 40 makes 1200 HC steps, above 1000",
        ),
        (["a.ply", "-o", "out", "--method", "taubin"], "invalid choice"),
        (["x/a.ply", "y/a.ply", "-o", "out"], "would both be written"),
        # Numbers that are not finite pass no range check by comparison: refused by name, before any file is read.
        (["a.ply", "-o", "out", "--tolerance", "inf"], "inf is not a finite number"),
        (["a.ply", "-o", "out", "--tolerance", "nan"], "nan is not a finite number"),
        (["a.ply", "-o", "out", "--alpha", "nan"], "nan is not a finite number"),
        (["a.ply", "-o", "out", "--beta=-inf"], "-inf is not a finite number"),
        (["a.ply", "-o", "out", "--points", "--reach", "inf"], "inf is not a finite number"),
        (["a.ply", "-o", "out", "--points", "--gap", "0"], "0 is below 0.1"),  # the operator's Gap minimum
        (["a.ply", "-o", "out", "--points", "--steps-per-round", "0"], "0 is below 1"),
        (["a.ply", "-o", "out", "--points", "--reach", "4"], "--reach (4) must not exceed --gap (3)"),
        (["a.ply", "-o", "out", "--points", "--gap", "2"], "--reach (2.5) must not exceed --gap (2)"),
        # --object picks objects inside .blend files; with none among the inputs it would do nothing.
        (["a.ply", "b.obj", "-o", "out", "--object", "Scan"], "no input is a .blend file"),
        # Mesh-only options mean nothing to the point smoother, and point options nothing to meshes.
        (["a.ply", "-o", "out", "--points", "--iterations", "20"], "--iterations does not apply to point clouds"),
        (
            [
                *("a.ply", "-o", "out", "--points", "--mode", "sequential", "--tolerance", "0.1"),
                *("--method", "laplacian", "--pin-boundary"),
            ],
            "--method, --mode, --tolerance, --pin-boundary do not apply to point clouds (--points): "
            "they take --alpha, --beta, --rounds",
        ),
        (
            ["a.ply", "-o", "out", "--rounds", "2", "--reach", "2"],
            "--rounds, --reach apply to point clouds only: add --points",
        ),
    ],
)
def test_usage_errors(tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(arguments.UsageError) as raised:
        arguments.parse(argv)
    assert message in str(raised.value)
    assert os.listdir(tmp_path) == []  # planning reads the file system, never writes to it


def test_point_steps_up_to_the_maximum_are_taken(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    most = spec.COMMAND_MAX_ITERATIONS
    plan = arguments.parse(["a.ply", "-o", "out", "--points", "--rounds", "10", "--steps-per-round", str(most // 10)])
    assert (plan.point_options["rounds"], plan.point_options["iterations_per_round"]) == (10, most // 10)
    plan = arguments.parse(["a.ply", "-o", "out", "--points", "--rounds", str(most)])
    assert plan.point_options["rounds"] == most


def test_a_good_command_line_makes_a_plan(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    plan = arguments.parse(["scan.ply", "scene.blend", "-o", "out", "--beta", "0.7", "--object", "Scan"])
    assert plan.files == [
        ("scan.ply", str(tmp_path / "out" / "scan.ply")),
        ("scene.blend", str(tmp_path / "out" / "scene.blend")),
    ]
    assert plan.settings.beta == 0.7 and plan.settings.auto_amount  # nothing fixes the amount: automatic
    assert plan.objects == ["Scan"] and not plan.points
    plan = arguments.parse(["scan.ply", "--in-place", "--iterations", "5", "--format", "OBJ"])
    assert plan.files == [("scan.ply", str(tmp_path / "scan.obj"))]
    assert plan.settings.iterations == 5 and not plan.settings.auto_amount
    plan = arguments.parse(["points.ply", "-o", "out", "--points", "--rounds", "2", "--alpha", "0.2"])
    assert plan.points and plan.point_options["rounds"] == 2 and plan.point_options["alpha"] == 0.2
    assert plan.point_options["auto_amount"] is False  # a manual amount, as the operator with alpha set
    plan = arguments.parse(
        ["scan.ply", "-o", "out", "--keep-sharp-edges", "--sharpness-angle", "45", "--iterations", "1000"]
    )
    assert plan.settings.sharpness_angle == pytest.approx(math.radians(45)) and plan.settings.iterations == 1000


def declared_options():
    """{option name: (setting, the arguments that make the option apply)} for every setting with a flag."""
    needs = {option: ["--" + needed.replace("_", "-")] for option, needed in arguments.NEEDS}
    options = {s.flag: (s, needs.get(s.flag.replace("-", "_"), [])) for s in spec.MESH if s.flag}
    options.update({s.flag: (s, ["--points"]) for s in spec.POINTS if s.flag and s.flag not in options})
    return options


def test_options_are_built_from_the_declarations(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    actions = {option: action for action in arguments.make_parser()._actions for option in action.option_strings}
    points = {s.flag: s for s in spec.POINTS if s.flag}
    for flag, (setting, extra) in declared_options().items():
        action = actions["--" + flag]
        assert action.help.startswith(setting.help), flag
        if setting.kind in ("float", "int", "enum"):
            assert action.default is None  # not given: the operator's default applies
            stated = [setting, points[flag]] if flag in points and points[flag] is not setting else [setting]
            for declared in stated:  # --help states the declared default (for shared options, both)
                assert arguments._default_text(declared) in action.help, flag
        if setting.kind == "enum":
            assert tuple(action.choices) == setting.identifiers
        # The declared limits: accepted on the limit, refused beyond it (--gap's minimum with a reach that fits).
        extra = extra + ["--reach", str(setting.min)] if flag == "gap" else extra
        degrees = setting.subtype == "ANGLE"  # given in degrees, held in radians
        for bound, beyond in ((setting.min, -1), (setting.max, 1)):
            if bound is None:
                continue
            shown = round(math.degrees(bound), 9) if degrees else bound
            plan = arguments.parse(["a.ply", "-o", "out", *extra, f"--{flag}", f"{shown:g}" if degrees else str(bound)])
            given = plan.point_options if "--points" in extra else vars(plan.settings)
            assert given[setting.name] == pytest.approx(bound, rel=1e-12), flag
            with pytest.raises(arguments.UsageError):
                arguments.parse(["a.ply", "-o", "out", *extra, f"--{flag}", str(shown + beyond)])
    assert set(arguments.MESH_ONLY) == {name.replace("-", "_") for name in declared_options() if name not in points}
    assert vars(arguments.Settings()) == {s.name: s.default for s in spec.MESH}


def test_slide_switches_keep_in_place_off(tmp_path, monkeypatch):
    """Keep in Place is on unless --slide is given; --slide is a mesh option, refused with --points."""
    monkeypatch.chdir(tmp_path)
    assert arguments.parse(["a.ply", "-o", "out"]).settings.keep_in_place is True
    plan = arguments.parse(["a.ply", "-o", "out", "--slide"])
    assert plan.settings.keep_in_place is False and "keep_in_place" in plan.given
    with pytest.raises(arguments.UsageError, match="--slide"):
        arguments.parse(["a.ply", "-o", "out", "--points", "--slide"])
