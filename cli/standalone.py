"""HC Smooth's package loaded from its folder without running its ``__init__`` (which registers the add-on
with Blender and imports bpy): how the file route runs in a Python without Blender
(scripts/hc_smooth_files.py) and, in task code, on the workers of a batch.

Standard library only: it is loaded by path, before the package exists.
"""

import importlib
import importlib.machinery
import importlib.util
import sys

NAME = "hc_smooth"  # the extension id (blender_manifest.toml): the package's name outside Blender


def load(root, name=NAME):
    """The package in folder ``root`` as module ``name``, its ``__init__`` not run, so that its modules
    import as ``name.cli``, ``name.jobs``, ``name.core``; the one already loaded under ``name`` if any."""
    package = sys.modules.get(name)
    if package is None:
        package = importlib.util.module_from_spec(importlib.machinery.ModuleSpec(name, None, is_package=True))
        package.__path__ = [str(root)]
        sys.modules[name] = package
    return package


def command(root, name=NAME):
    """The command's module (cli/command.py) of the package in ``root``."""
    load(root, name)
    return importlib.import_module(f"{name}.cli.command")


def sent(function, *args):
    """``function(*args)`` as bytes that run it where ``pickle.loads`` reads them: a task any Dask worker can
    run with the standard library alone (the worker is given ``pickle.loads`` and these bytes). The functions
    of this module travel as code (cloudpickle by value), so a worker needs nothing of HC Smooth but its
    folder; their results come back as classes of the package loaded as ``NAME``."""
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    return cloudpickle.dumps(_Call(function, args))


class _Call:
    """Unpickling it calls ``function(*args)``: what ``sent`` pickles."""

    def __init__(self, function, args):
        self.function, self.args = function, args

    def __reduce__(self):
        return self.function, self.args


def on_worker(root, *args):
    """On a batch's worker: cli/batch.py's ``smooth_task(*args)`` of the package in ``root``."""
    load(root)
    return importlib.import_module(f"{NAME}.cli.batch").smooth_task(*args)


def on_worker_tile(root, job):
    """On a worker: cli/tiled.py's ``run_tile`` of a tiled file's ``job`` (a TileJob pickled by the worker that
    runs the file, whose classes import once the package in ``root`` is loaded)."""
    import pickle

    load(root)
    importlib.import_module(f"{NAME}.cli.batch").heap_for_large_arrays()
    return importlib.import_module(f"{NAME}.cli.tiled").run_tile(pickle.loads(job))


def problem(root):
    """Why this process cannot run the package in ``root`` (on a worker: what it lacks), or None."""
    import os

    if not os.path.isfile(os.path.join(root, "cli", "file_route.py")):
        return f"no HC Smooth at {root} (workers need it at the same path)"
    for module in ("numpy", "scipy"):
        if importlib.util.find_spec(module) is None:
            return f"no {module} in {sys.executable}"
    return None
