"""core and settings_spec load without Blender: tools and the command line import them in plain Python.

Each import runs in a fresh interpreter (this one may have loaded bpy for other tests). In the bpy
environments Blender's modules are importable, so an import of one anywhere below would succeed and
show up in sys.modules; elsewhere it would fail the import.
"""

import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BLENDER_MODULES = ("bpy", "_bpy", "bmesh", "mathutils", "bpy_extras", "gpu", "gpu_extras", "bl_operators", "bl_ui")

# Every module of the package, not only what its __init__ pulls in.
IMPORT_ALL = """
import importlib, pkgutil, sys
sys.path.insert(0, sys.argv[1])
package = importlib.import_module(sys.argv[2])
for module in pkgutil.walk_packages(getattr(package, "__path__", []), package.__name__ + "."):
    importlib.import_module(module.name)
print(len([name for name in sys.modules if name.split(".")[0] == package.__name__]))
print(" ".join(sorted({name.split(".")[0] for name in sys.modules} & set(sys.argv[3].split()))))
"""


@pytest.mark.parametrize("package, least_modules", [("core", 10), ("settings_spec", 1)])
def test_import_loads_no_blender_module(package, least_modules):
    result = subprocess.run(
        [sys.executable, "-c", IMPORT_ALL, str(ROOT), package, " ".join(BLENDER_MODULES)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    loaded, blender = result.stdout.split("\n")[:2]
    assert int(loaded) >= least_modules  # the walk really imported the package's modules
    assert blender == "", f"importing {package} loaded Blender modules: {blender}"
