"""Build the extension zip with Blender's own extension tool (run with a Python that has the bpy module).

    python scripts/build_extension.py [--output-dir build] [--split-platforms]

Prints the path of each zip built.
"""

import argparse
import importlib.util
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]


def blender_ext_tool():
    """Blender's extension CLI (blender_ext.py) inside the installed bpy module; it runs with plain Python."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("the bpy module is not installed in this Python (run `make envs`)")
    found = sorted(pathlib.Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise SystemExit(f"Blender's extension tool not found under {pathlib.Path(spec.origin).parent}")
    return found[-1]


def build(output_dir, split_platforms=False):
    output_dir = pathlib.Path(output_dir).resolve()
    output_dir.mkdir(parents=True, exist_ok=True)
    before = set(output_dir.glob("*.zip"))
    command = [
        sys.executable,
        str(blender_ext_tool()),
        "build",
        "--source-dir",
        str(ROOT),
        "--output-dir",
        str(output_dir),
    ]
    if split_platforms:
        command.append("--split-platforms")
    subprocess.run(command, check=True)
    built = sorted(set(output_dir.glob("*.zip")) - before) or sorted(output_dir.glob("hc_smooth-*.zip"))
    return built


def validate(path):
    subprocess.run([sys.executable, str(blender_ext_tool()), "validate", str(path)], check=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output-dir", default=str(ROOT / "build"))
    parser.add_argument("--split-platforms", action="store_true")
    args = parser.parse_args()
    for path in build(args.output_dir, args.split_platforms):
        validate(path)
        print(path)


if __name__ == "__main__":
    main()
