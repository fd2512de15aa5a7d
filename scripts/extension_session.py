"""For scripts that run HC Smooth in the bpy module (demo, benchmarks): install the extension the way
a user does, into a throw-away Blender user folder, and leave the process safely (removing that folder).

Import this module before bpy: Blender reads its user folder once, when bpy is first imported.
"""

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

# Always a fresh folder, even when the caller has one (a test session's): never install over theirs.
USER_RESOURCES = tempfile.mkdtemp(prefix="hc_smooth_user_")
os.environ["BLENDER_USER_RESOURCES"] = USER_RESOURCES
# Blender's thumbnail cache ($XDG_CACHE_HOME/thumbnails) goes there too, not into the home folder.
os.environ["XDG_CACHE_HOME"] = os.path.join(USER_RESOURCES, "cache")

import bpy  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
ADDON = "bl_ext.user_default.hc_smooth"


def install_extension(build_dir):
    """Build the zip with Blender's extension tool into ``build_dir``, install and enable it, then delete
    the zip (and ``build_dir`` if that leaves it empty): the installed copy is what runs. Returns the
    zip's path."""
    build_dir = pathlib.Path(build_dir)
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "build_extension.py"), "--output-dir", str(build_dir)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    zip_path = out.strip().splitlines()[-1]
    try:
        result = bpy.ops.extensions.package_install_files(
            filepath=zip_path, repo="user_default", enable_on_install=True
        )
    finally:
        os.unlink(zip_path)
        if not any(build_dir.iterdir()):
            build_dir.rmdir()
    if result != {"FINISHED"} or ADDON not in sys.modules:
        raise SystemExit(f"could not install {zip_path}")
    return zip_path


def run_and_exit(main):
    """Run ``main()`` and end the process with its status, skipping C exit handlers: bpy 4.5 can
    deadlock in them (see tests/conftest.py)."""
    status = 0
    try:
        main()
    except SystemExit as exit_:
        status = exit_.code if isinstance(exit_.code, int) else 1
        if not isinstance(exit_.code, int) and exit_.code is not None:
            print(exit_.code, file=sys.stderr)
    except Exception:  # noqa: BLE001 - print the trace, then leave through the same door
        import traceback

        traceback.print_exc()
        status = 1
    sys.stdout.flush()
    sys.stderr.flush()
    shutil.rmtree(USER_RESOURCES, ignore_errors=True)
    shutil.rmtree(bpy.app.tempdir, ignore_errors=True)  # Blender removes it at exit, which os._exit skips
    os._exit(status)
