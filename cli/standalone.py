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
