#!/usr/bin/env bash
# Create the test environments, each with Blender as a Python module (bpy) from PyPI:
#   .envs/bpy45  Blender 4.5 LTS, Python 3.11, NumPy 1.26 (as Blender 4.x bundles), SciPy 1.15
#   .envs/bpy52  Blender 5.2 LTS, Python 3.13, NumPy 2.x,  SciPy 1.17
# and the others the Makefile names:
#   .envs/lint   ruff
#   .envs/bench  the benchmarks' peers (bench/requirements.txt; Open3D needs Debian's libusb-1.0-0)
#   bash scripts/setup_envs.sh [bpy45] [bpy52] [lint] [bench]     (no argument: bpy45 and bpy52)
# Idempotent: an environment whose stamp matches its requirements is left alone.
# pip's own cache is off: the environments are the only copy, nothing is written outside the repository.
set -euo pipefail
cd "$(dirname "$0")/.."

find_python() {  # find_python 3.11 -> a working python3.11 (pyenv's install first: its PATH shims may refuse)
    local version=$1 candidate
    for candidate in "$(pyenv root 2>/dev/null)/versions/$version"*/bin/"python$version" "python$version"; do
        if "$candidate" --version >/dev/null 2>&1; then command -v "$candidate"; return; fi
    done
    echo "setup_envs: Python $version not found (install it, e.g. with pyenv)" >&2
    return 1
}

make_env() {  # make_env NAME PYTHON_VERSION REQUIREMENTS...
    local name=$1 version=$2; shift 2
    local dir=.envs/$name stamp
    stamp="$*${STAMP_EXTRA:+ $STAMP_EXTRA}"
    if [ -f "$dir/.stamp" ] && [ "$(cat "$dir/.stamp")" = "$stamp" ]; then
        echo "setup_envs: $dir is up to date"
        return
    fi
    echo "setup_envs: creating $dir ($*)"
    rm -rf "$dir"
    "$(find_python "$version")" -m venv "$dir"
    "$dir/bin/python" -m pip install --quiet --no-cache-dir --upgrade pip 2>&1 | grep -v "is ignored: it is neither" || true
    "$dir/bin/python" -m pip install --quiet --no-cache-dir "$@" 2>&1 | grep -v "is ignored: it is neither" || true
    case $name in  # fail here, not in the tests
        bpy*) "$dir/bin/python" -c "import bpy, numpy, scipy, pytest, hypothesis, distributed" ;;
        bench) "$dir/bin/python" -c "import numpy, scipy, trimesh, pymeshlab, open3d, CGAL, meshlib, vtk, distributed" ;;
    esac
    echo "$stamp" > "$dir/.stamp"
}

libusb() {  # Open3D (a peer of the benchmarks) loads libusb-1.0 when imported: Debian's package, if missing
    if ldconfig -p | grep -q "libusb-1.0.so.0"; then return; fi
    echo "setup_envs: installing Debian's libusb-1.0-0 (Open3D needs it)"
    if [ "$(id -u)" = 0 ]; then apt-get install -y -qq libusb-1.0-0 >/dev/null || { apt-get update -qq && apt-get install -y -qq libusb-1.0-0 >/dev/null; }
    else sudo apt-get install -y -qq libusb-1.0-0 >/dev/null; fi
}

# dask[distributed]: the batches of --jobs and --scheduler (cli/batch.py) and their tests.
TEST_TOOLS=(pytest==9.* hypothesis==6.* "dask[distributed]==2026.8.*")
[ $# -gt 0 ] || set -- bpy45 bpy52
for name in "$@"; do
    case $name in
        bpy45) make_env bpy45 3.11 "bpy==4.5.*" "numpy==1.26.*" "scipy==1.15.*" "${TEST_TOOLS[@]}" ;;
        bpy52) make_env bpy52 3.13 "bpy==5.2.*" "numpy>=2.2,<2.7" "scipy==1.17.*" "${TEST_TOOLS[@]}" ;;
        lint) make_env lint 3.11 "ruff==0.17.*" ;;
        bench)
            libusb
            # The stamp holds the requirements file's text, so a changed pin rebuilds the environment.
            STAMP_EXTRA="$(sha256sum bench/requirements.txt | cut -c1-16)" make_env bench 3.11 -r bench/requirements.txt ;;
        *) echo "setup_envs: unknown environment $name (bpy45, bpy52, lint, bench)" >&2; exit 2 ;;
    esac
done
