"""Per-platform extension zips with SciPy bundled as wheels (run with a Python that has the bpy module).

    python scripts/dist.py [--output-dir dist] [--cache build/wheels] [--platform linux-x64 ...]

1. Downloads SciPy wheels (no dependencies: Blender bundles NumPy, never ship it) for every platform
   (or those given with --platform) and Python that Blender 4.2+ uses, into a cache that later runs
   reuse (~35 MB per wheel; all eight ~270 MB).
2. Stages a copy of the package with those wheels and a generated manifest listing them (the
   committed blender_manifest.toml stays wheel-free, so plain `make build` works offline), in a
   temporary folder that is removed afterwards.
3. Builds one zip per platform with Blender's own tool (`build --split-platforms`), validates each
   and checks what went in. Each zip carries the wheels of both Pythons; at install time Blender
   keeps only the wheel matching its own Python version and platform.
"""

import argparse
import pathlib
import shutil
import subprocess
import sys
import tempfile
import tomllib
import zipfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from build_extension import ROOT, blender_ext_tool  # noqa: E402

# (Python version, SciPy requirement). Blender 4.2-5.0 run Python 3.11 with NumPy 1.2x-2.x: SciPy 1.15.3
# supports NumPy >= 1.23.5, < 2.5. Blender 5.1+ run Python 3.13 with NumPy 2.x (2.5 in 5.2): SciPy 1.17.
PYTHONS = (("3.11", "scipy==1.15.3"), ("3.13", "scipy==1.17.*"))
# Blender platform -> pip --platform tags, best first (pip does not expand manylinux versions itself).
# Blender needs glibc >= 2.28 on Linux and macOS >= 11.2; SciPy's arm64 wheels need macOS 12.
PLATFORMS = {
    "windows-x64": ("win_amd64",),
    "macos-x64": ("macosx_11_0_x86_64",),
    "macos-arm64": ("macosx_12_0_arm64",),
    "linux-x64": ("manylinux_2_28_x86_64", "manylinux_2_27_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64"),
}
# Never copied into the staging folder (the manifest's paths_exclude_pattern filters the rest).
STAGING_IGNORE = shutil.ignore_patterns(
    ".git",
    ".envs",
    "build",
    "dist",
    "demo_output",
    ".hypothesis",
    ".pytest_cache",
    ".benchmarks",
    "__pycache__",
    "*.zip",
)


def download_wheels(cache, platforms=tuple(PLATFORMS)):
    """One SciPy wheel per (Python, platform), downloaded once into ``cache/<python>-<platform>/``."""
    wheels = []
    for python, requirement in PYTHONS:
        for platform in platforms:
            tags = PLATFORMS[platform]
            folder = cache / f"cp{python.replace('.', '')}-{platform}"
            found = sorted(folder.glob("scipy-*.whl"))
            if not found:
                folder.mkdir(parents=True, exist_ok=True)
                command = [
                    sys.executable,
                    "-m",
                    "pip",
                    "download",
                    "--quiet",
                    "--disable-pip-version-check",
                    "--only-binary=:all:",
                    "--no-deps",
                    "--no-cache-dir",
                    "--implementation",
                    "cp",
                    "--python-version",
                    python,
                    "--dest",
                    str(folder),
                    requirement,
                ]
                for tag in tags:
                    command += ["--platform", tag]
                print(f"dist: downloading {requirement} for Python {python} on {platform}", flush=True)
                subprocess.run(command, check=True)
                found = sorted(folder.glob("scipy-*.whl"))
            if len(found) != 1:
                raise SystemExit(
                    f"dist: expected one SciPy wheel in {folder}, found {[p.name for p in found]}: "
                    "delete the folder and run again"
                )
            wheels.append(found[0])
    return wheels


def manifest_with_wheels(text, wheel_names, platforms=tuple(PLATFORMS)):
    """The manifest text with `platforms` and `wheels` added as top-level keys (before the first table)."""
    data = tomllib.loads(text)
    if "wheels" in data or "platforms" in data:
        raise SystemExit("dist: blender_manifest.toml already lists wheels or platforms; remove them (dist adds both)")
    lines = text.splitlines(keepends=True)
    first_table = next((i for i, line in enumerate(lines) if line.lstrip().startswith("[")), len(lines))
    added = [
        "# Added by scripts/dist.py: SciPy for these platforms (NumPy comes with Blender).\n",
        "platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]\n",
        "wheels = [\n",
        *(f'  "./wheels/{name}",\n' for name in wheel_names),
        "]\n\n",
    ]
    result = "".join(lines[:first_table] + added + lines[first_table:])
    parsed = tomllib.loads(result)
    assert parsed["wheels"] == [f"./wheels/{name}" for name in wheel_names] and parsed["platforms"] == list(platforms)
    return result


def stage(wheels, staging, platforms=tuple(PLATFORMS)):
    shutil.copytree(ROOT, staging, ignore=STAGING_IGNORE)
    (staging / "wheels").mkdir()
    for wheel in wheels:
        shutil.copy2(wheel, staging / "wheels" / wheel.name)
    manifest = staging / "blender_manifest.toml"
    manifest.write_text(manifest_with_wheels(manifest.read_text(), [wheel.name for wheel in wheels], platforms))


def build(staging, output_dir):
    output_dir.mkdir(parents=True, exist_ok=True)
    for old in output_dir.glob("hc_smooth-*.zip"):
        old.unlink()
    tool = str(blender_ext_tool())
    subprocess.run(
        [
            sys.executable,
            tool,
            "build",
            "--split-platforms",
            "--source-dir",
            str(staging),
            "--output-dir",
            str(output_dir),
        ],
        check=True,
    )
    zips = sorted(output_dir.glob("hc_smooth-*.zip"))
    for path in zips:
        subprocess.run([sys.executable, tool, "validate", str(path)], check=True)
        check_zip(path)
    return zips


def check_zip(path):
    """Exactly the SciPy wheels of its platform (one per Python), no NumPy, none of the development files."""
    platform = next((p for p in PLATFORMS if path.stem.endswith(p.replace("-", "_")) or path.stem.endswith(p)), None)
    if platform is None:
        raise SystemExit(f"dist: {path.name} is not named after one of {list(PLATFORMS)}")
    names = zipfile.ZipFile(path).namelist()
    wheels = sorted(name for name in names if name.endswith(".whl"))
    pythons = sorted(name.split("-")[2] for name in wheels)
    problems = []
    if pythons != ["cp311", "cp313"] or not all(name.startswith("wheels/scipy-") for name in wheels):
        problems.append(f"wheels {wheels}")
    if any("numpy" in name.lower() for name in names):
        problems.append("NumPy is bundled")
    for folder in ("tests/", "bench/", "docs/", "examples/", "scripts/", ".ci/", "demo/", ".envs/"):
        if any(name.startswith(folder) for name in names):
            problems.append(f"{folder} is bundled")
    if problems:
        raise SystemExit(f"dist: {path.name}: " + "; ".join(problems))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output-dir", default=str(ROOT / "dist"))
    parser.add_argument("--cache", default=str(ROOT / "build" / "wheels"), help="downloaded wheels (reused)")
    parser.add_argument(
        "--platform",
        action="append",
        choices=list(PLATFORMS),
        help="build only this platform's zip (repeatable; default: all)",
    )
    args = parser.parse_args()
    platforms = tuple(args.platform or PLATFORMS)
    wheels = download_wheels(pathlib.Path(args.cache), platforms)
    with tempfile.TemporaryDirectory(prefix="hc_smooth_dist_") as work:
        staging = pathlib.Path(work) / "hc_smooth"
        stage(wheels, staging, platforms)
        zips = build(staging, pathlib.Path(args.output_dir))
    for path in zips:
        print(f"{path}  {path.stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
