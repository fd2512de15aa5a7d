"""The smoothing arguments are declared and described once (core.Smoothing) and every entry point
that passes them on takes exactly those, as it did when each wrote them out."""

import inspect
import re

import numpy as np
import pytest

import core
from core import smoothing

POSITIONS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
EDGES = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
REQUIRED = inspect.Parameter.empty
ARRAYS = {"positions": REQUIRED, "edges": REQUIRED}
OWN = {  # each entry point's own arguments and their defaults; the rest comes through **options
    core.smooth: ARRAYS
    | {
        "method": "hc",
        "alpha": core.DEFAULT_ALPHA,
        "beta": core.DEFAULT_BETA,
        "iterations": REQUIRED,
        "progress": None,
    },
    core.hc_smooth: ARRAYS | {"alpha": REQUIRED, "beta": REQUIRED, "iterations": REQUIRED},
    core.laplacian_smooth: ARRAYS | {"variant": "plain", "alpha": 0.0, "iterations": REQUIRED},
}
SMOOTHING = ARRAYS | {  # core.Smoothing's, the one declaration of the options
    "method": "hc",
    "alpha": core.DEFAULT_ALPHA,
    "beta": core.DEFAULT_BETA,
    "iterations": REQUIRED,
    "mode": "simultaneous",
    "fixed": None,
    "tolerance": 0.0,
    "original": None,
    "operator": None,
    "influence": None,
    "max_deviation": 0.0,
    "stacklevel": 2,
}


def parameters(function):
    return inspect.signature(function).parameters


def documented(function):
    """The names of the entries ("name : type") in the Parameters and Other Parameters sections."""
    sections = re.split(r"^(.+)\n-+$", function.__doc__, flags=re.M)  # [intro, title, body, title, body, ...]
    bodies = [body for title, body in zip(sections[1::2], sections[2::2]) if title.endswith("Parameters")]
    return {
        name for body in bodies for names in re.findall(r"^(\w+(?:, \w+)*) :", body, re.M) for name in names.split(", ")
    }


def test_the_options_are_what_smoothing_takes_besides_the_numbers():
    assert {name: parameter.default for name, parameter in parameters(core.Smoothing).items()} == SMOOTHING
    options = set(SMOOTHING) - {"positions", "edges", "method", "alpha", "beta", "iterations", "stacklevel"}
    assert smoothing.SmoothingOptions.__optional_keys__ == options
    assert smoothing.SmoothOptions.__optional_keys__ == options | {"progress"}


@pytest.mark.parametrize("function", OWN, ids=lambda function: function.__name__)
def test_entry_points_take_their_own_arguments_keyword_only_and_pass_the_rest(function):
    given = dict(parameters(function))
    assert given.pop("options").kind is inspect.Parameter.VAR_KEYWORD
    assert {name: parameter.default for name, parameter in given.items()} == OWN[function]
    assert [parameter.kind for parameter in given.values()][2:] == [inspect.Parameter.KEYWORD_ONLY] * (len(given) - 2)


@pytest.mark.parametrize("function", [core.Smoothing, *OWN], ids=lambda function: function.__name__)
def test_every_argument_is_described_and_no_placeholder_is_left(function):
    accepted = set(parameters(function)) - {"options"}
    if function is not core.Smoothing:
        passed_on = smoothing.SmoothingOptions if function is core.smooth else smoothing.SmoothOptions
        accepted |= passed_on.__optional_keys__
    assert documented(function) == accepted
    assert not re.search(r"\{(arrays|numbers|options|progress|raises)\}", function.__doc__)


@pytest.mark.parametrize(
    ("function", "name"),
    [
        (core.hc_smooth, "method"),
        (core.hc_smooth, "variant"),
        (core.hc_smooth, "stacklevel"),
        (core.laplacian_smooth, "beta"),
        (core.laplacian_smooth, "method"),
        (core.smooth, "variant"),
        (core.smooth, "stacklevel"),
        (core.smooth, "tolerence"),
    ],
)
def test_an_argument_the_entry_point_does_not_take_is_refused_by_its_name(function, name):
    numbers = {"alpha": 0.1, "iterations": 1} | ({} if function is core.laplacian_smooth else {"beta": 0.6})
    with pytest.raises(TypeError, match=rf"^{function.__name__}\(\) got an unexpected keyword argument '{name}'$"):
        function(POSITIONS, EDGES, **numbers, **{name: 0})


def test_passed_on_arguments_reach_the_run():
    fixed_and_progress = []
    result = core.hc_smooth(
        POSITIONS,
        EDGES,
        alpha=0.1,
        beta=0.6,
        iterations=3,
        fixed=[0],
        progress=lambda *done: fixed_and_progress.append(done),
    )
    assert np.array_equal(result[0], POSITIONS[0]) and not np.array_equal(result[1:], POSITIONS[1:])
    assert fixed_and_progress == [(1, 3), (2, 3), (3, 3)]
    sequential = core.laplacian_smooth(POSITIONS, EDGES, iterations=1, mode="sequential")
    assert not np.array_equal(sequential, core.laplacian_smooth(POSITIONS, EDGES, iterations=1))
