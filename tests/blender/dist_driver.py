"""Run in a fresh process by test_dist.py: install a built platform zip into an empty Blender user
folder (the way Blender installs extensions), then report as JSON which SciPy is imported and whether
the operator and the command work from that installation.

Blender's own Python has no SciPy, but the test environment has one, and with the bpy module Blender
appends the extensions' site-packages after the environment's: so the environment's SciPy is hidden
here, as a real Blender would not have it.

    python dist_driver.py ZIP WORKDIR
"""

import importlib.abc
import importlib.machinery
import importlib.util
import json
import os
import pathlib
import shutil
import sys

zip_path, work = sys.argv[1], pathlib.Path(sys.argv[2])
ENV_SITE_PACKAGES = [path for path in sys.path if path.rstrip("/").endswith("site-packages")]


class HideEnvironmentSciPy(importlib.abc.MetaPathFinder):
    """Make this process look like Blender's own Python, which has NumPy but no SciPy: `scipy` is looked
    up everywhere except the test environment's site-packages (its submodules follow the package)."""

    def find_spec(self, name, path=None, target=None):
        if name != "scipy":
            return None
        spec = importlib.machinery.PathFinder.find_spec(
            name, [entry for entry in sys.path if entry not in ENV_SITE_PACKAGES]
        )
        if spec is None:  # stop here: the finders after this one would find the environment's
            raise ModuleNotFoundError("No module named 'scipy' (the test environment's is hidden)", name=name)
        return spec


sys.meta_path.insert(0, HideEnvironmentSciPy())
os.environ["BLENDER_USER_RESOURCES"] = str(work / "user")  # read once, at the bpy import

import bpy  # noqa: E402
import numpy as np  # noqa: E402

report = {}
try:
    report["env_scipy_exists"] = any(os.path.isdir(os.path.join(path, "scipy")) for path in ENV_SITE_PACKAGES)
    try:
        report["scipy_before_install"] = importlib.util.find_spec("scipy").origin
    except ModuleNotFoundError:
        report["scipy_before_install"] = None
    assert "scipy" not in sys.modules, "SciPy was imported before the extension was installed"
    result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
    report["install"] = sorted(result)
    package = "bl_ext.user_default.hc_smooth"
    report["enabled"] = package in bpy.context.preferences.addons
    site = (
        work
        / "user"
        / "extensions"
        / ".local"
        / "lib"
        / f"python{sys.version_info[0]}.{sys.version_info[1]}"
        / "site-packages"
    )
    report["site_packages"] = str(site)
    report["dist_infos"] = sorted(path.name for path in site.glob("*.dist-info")) if site.is_dir() else []
    import scipy.sparse  # what the extension's core imports

    report["scipy_file"] = scipy.__file__
    report["scipy_sparse_file"] = scipy.sparse.__file__
    report["scipy_version"] = scipy.__version__

    # The operator from the installed zip.
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3)
    obj = bpy.context.active_object
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    co += np.random.default_rng(0).normal(scale=0.02, size=co.shape).astype(np.float32)
    obj.data.vertices.foreach_set("co", co)
    obj.data.update()
    report["operator"] = sorted(bpy.ops.object.hc_smooth(auto_amount=False, iterations=10))
    after = np.empty_like(co)
    obj.data.vertices.foreach_get("co", after)
    report["operator_moved"] = int(np.count_nonzero(np.any((after != co).reshape(-1, 3), axis=1)))

    # The command's entry function from the installed zip.
    bpy.ops.wm.stl_export(filepath=str(work / "scan.stl"))
    command = sys.modules[package + ".cli"].main
    report["command_status"] = command([str(work / "scan.stl"), "-o", str(work / "out")])
    report["command_outputs"] = sorted(os.listdir(work / "out"))
    report["extension_core_file"] = sys.modules[package + ".core"].__file__
    bpy.ops.preferences.addon_disable(module=package)  # bpy 4.5 can hang at exit with classes registered
except Exception as error:  # reported to the test, which fails with it
    report["error"] = f"{type(error).__name__}: {error}"
finally:
    print("REPORT " + json.dumps(report), flush=True)
    sys.stderr.flush()
    shutil.rmtree(bpy.app.tempdir, ignore_errors=True)  # Blender removes it at exit, which os._exit skips
    os._exit(0)  # bpy 4.5 can deadlock in C exit handlers (see tests/conftest.py)
