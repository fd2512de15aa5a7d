"""Headless Blender (the bpy module) with HC Smooth installed the way Blender installs extensions:
the zip built by Blender's own extension tool, then package_install_files into a clean user folder."""

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

# Blender reads its user folder once, when bpy is first imported: point it at an empty one. Subprocesses
# inherit it, and Blender's thumbnail cache ($XDG_CACHE_HOME/thumbnails): nothing goes to the home folder.
USER_RESOURCES = tempfile.mkdtemp(prefix="hc_smooth_user_")
os.environ["BLENDER_USER_RESOURCES"] = USER_RESOURCES
os.environ["XDG_CACHE_HOME"] = os.path.join(USER_RESOURCES, "cache")

import bpy  # noqa: E402
import pytest  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
from blender_scene import ADDON  # noqa: E402

sys.path.insert(0, str(ROOT))  # `import core` (the same code, loaded outside Blender) for comparisons


def pytest_sessionfinish(session, exitstatus):
    # tests/conftest.py ends the process with os._exit, which skips Blender's removal of its temp folder.
    shutil.rmtree(USER_RESOURCES, ignore_errors=True)
    shutil.rmtree(bpy.app.tempdir, ignore_errors=True)


@pytest.fixture(scope="session")
def extension_zip(tmp_path_factory):
    out = tmp_path_factory.mktemp("build")
    subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "build_extension.py"), "--output-dir", str(out)],
        check=True,
        capture_output=True,
    )
    (path,) = out.glob("hc_smooth-*.zip")
    return path


@pytest.fixture(scope="session")
def addon(extension_zip):
    result = bpy.ops.extensions.package_install_files(
        filepath=str(extension_zip), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}
    yield sys.modules[ADDON]
    # bpy 4.5 can hang at interpreter exit while operator classes are still registered.
    bpy.ops.preferences.addon_disable(module=ADDON)


@pytest.fixture
def scene(addon):
    """An empty scene with the add-on enabled."""
    bpy.ops.wm.read_homefile(use_empty=True)
    return bpy.context.scene
