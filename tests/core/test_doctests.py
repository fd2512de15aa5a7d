"""The examples in core's docstrings run and print what they say, and every public name has one.

CI runs this file on both environments, so the examples print the same under NumPy 1.26 and 2.x.
"""

import doctest
import importlib
import inspect
import pkgutil
import warnings

import pytest

import core

MODULES = ["core"] + sorted(info.name for info in pkgutil.walk_packages(core.__path__, "core."))
# Modules, classes and functions; the constants among the public names (METHODS, DEFAULT_ALPHA, ...)
# have no docstring of their own.
PUBLIC = [
    (owner.__name__, name)
    for owner in (core, core.mesh, core.pointcloud)
    for name in owner.__all__
    if inspect.ismodule(getattr(owner, name)) or callable(getattr(owner, name))
]


def examples(thing):
    """The doctest examples of a module (all its docstrings) or of one class or function."""
    return [example for test in doctest.DocTestFinder().find(thing) for example in test.examples]


@pytest.mark.parametrize("name", MODULES)
def test_examples_print_what_they_say(name):
    module = importlib.import_module(name)
    with warnings.catch_warnings():
        warnings.simplefilter("error", core.ConvergenceWarning)  # an example that warns says so itself
        results = doctest.testmod(module, verbose=False)
    assert results.failed == 0, f"{results.failed} of {results.attempted} examples in {name} failed (see above)"


def test_the_modules_and_names_are_found():
    assert {"core.smoothing", "core.mesh.smooth", "core.pointcloud.smooth"} <= set(MODULES)
    assert {("core", "hc_smooth"), ("core.mesh", "smooth_mesh"), ("core.pointcloud", "rfs_mesh")} <= set(PUBLIC)


@pytest.mark.parametrize(("owner", "name"), PUBLIC)
def test_public_names_have_examples(owner, name):
    thing = getattr(importlib.import_module(owner), name)
    assert examples(thing), f"{owner}.{name} has no >>> example"
    if not inspect.ismodule(thing):
        assert "Examples\n--------" in inspect.getdoc(thing), f"{owner}.{name} has no numpydoc Examples section"
