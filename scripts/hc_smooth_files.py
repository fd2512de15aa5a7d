"""HC Smooth on scan files without Blender: PLY, OBJ and STL, in any Python with NumPy and SciPy.

    python scripts/hc_smooth_files.py scans/ -o smoothed/
    python scripts/hc_smooth_files.py scans/*.ply -o smoothed/ --iterations 20
    python scripts/hc_smooth_files.py --help

It runs the code of `blender -b -c hc_smooth` (the extension's cli/ and jobs/, loaded from this
repository without Blender): the same options, the same messages and exit status, the same output bytes
(docs/command_line.md). .blend files need Blender: `blender -b -c hc_smooth`.
"""

import importlib.util
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]  # the extension's folder: this repository


def standalone():
    """cli/standalone.py, loaded by path (it loads the package)."""
    spec = importlib.util.spec_from_file_location("hc_smooth_standalone", ROOT / "cli" / "standalone.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(argv):
    try:
        import numpy  # noqa: F401
        import scipy  # noqa: F401
    except ModuleNotFoundError as error:
        print(
            f"hc_smooth_files: this Python ({sys.executable}) has no {error.name}, which HC Smooth needs: "
            "python -m pip install numpy scipy",
            file=sys.stderr,
        )
        return 2
    return standalone().command(ROOT).main(argv, prog=f"python {sys.argv[0]}")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
