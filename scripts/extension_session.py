"""For scripts that run HC Smooth in the bpy module (demo, benchmarks): install the extension the way
a user does, into a throw-away Blender user folder, and leave the process safely.

Import this module before bpy: Blender reads its user folder once, when bpy is first imported.
"""

import os
import pathlib
import subprocess
import sys
import tempfile

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="hc_smooth_user_"))

import bpy  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
ADDON = "bl_ext.user_default.hc_smooth"


def install_extension(build_dir):
    """Build the zip with Blender's extension tool, install and enable it; returns the zip's path."""
    out = subprocess.run([sys.executable, str(ROOT / "scripts" / "build_extension.py"), "--output-dir",
                          str(build_dir)], check=True, capture_output=True, text=True).stdout
    zip_path = out.strip().splitlines()[-1]
    result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                      enable_on_install=True)
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
    os._exit(status)
