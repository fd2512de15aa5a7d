"""A stand-in for `blender -b -c hc_smooth ARGS...` made of the bpy module (there is no blender binary
here, and the bpy module cannot run `-c`): import bpy with the user folder in BLENDER_USER_RESOURCES,
where HC Smooth is installed and enabled, and call the registered command's entry function.

    python blender_c.py --install ZIP          install the extension into the user folder
    python blender_c.py hc_smooth ARGS...      run the command like `blender -b -c hc_smooth ARGS...`
"""

import os
import sys

import bpy

PACKAGE = "bl_ext.user_default.hc_smooth"


def main(argv):
    if argv[:1] == ["--install"]:
        bpy.ops.extensions.package_install_files(filepath=argv[1], repo="user_default", enable_on_install=True)
        return 0 if PACKAGE in bpy.context.preferences.addons else 1
    if argv[:1] != ["hc_smooth"]:
        print(__doc__, file=sys.stderr)
        return 2
    # Blender enables installed extensions at start-up from the saved preferences; the bpy module does
    # not load them, so enable the installed copy here (loaded from the user folder, not reinstalled).
    if PACKAGE not in bpy.context.preferences.addons:
        try:
            bpy.ops.preferences.addon_enable(module=PACKAGE)
        except RuntimeError as error:
            print(f"HC Smooth is not installed in {os.environ.get('BLENDER_USER_RESOURCES')}: {error}",
                  file=sys.stderr)
            return 1
    return sys.modules[PACKAGE + ".cli"].main(argv[1:])


if __name__ == "__main__":
    status = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)  # bpy 4.5 can deadlock in C exit handlers (see tests/conftest.py)
