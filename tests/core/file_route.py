"""The file route without Blender, as a user runs it: scripts/hc_smooth_files.py in a subprocess where
Blender's modules cannot be imported (a finder first on sys.meta_path refuses them, as a Python without
bpy would), and a folder of scan files of every kind it reads. Plain NumPy."""

import pathlib
import subprocess
import sys

import numpy as np
import scan_files

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "hc_smooth_files.py"
BLENDER_MODULES = ("bpy", "_bpy", "bmesh", "mathutils", "bpy_extras", "gpu", "bl_operators", "bl_ui")

# Runs the script (argv[1]) on argv[2:] with Blender's modules unimportable; at exit, says which of them
# were loaded (none can be: an import of one raises).
WITHOUT_BLENDER = f"""
import os, runpy, sys
BLOCKED = {BLENDER_MODULES!r} + tuple(filter(None, os.environ.get("TEST_BLOCKED", "").split()))

class NoBlender:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None

sys.meta_path.insert(0, NoBlender())
script, sys.argv = sys.argv[1], sys.argv[1:]
try:
    runpy.run_path(script, run_name="__main__")
finally:
    sys.stderr.write("loaded: " + " ".join(sorted({{m.split(".")[0] for m in sys.modules}} & set(BLOCKED))) + "\\n")
"""


def without_blender(args, script=SCRIPT):
    """The command line that runs scripts/hc_smooth_files.py ``args`` where bpy cannot be imported (nor the
    modules named in the environment's TEST_BLOCKED)."""
    return [sys.executable, "-c", WITHOUT_BLENDER, str(script), *map(str, args)]


def run_without_blender(args, cwd, script=SCRIPT, timeout=600, env=None):
    """scripts/hc_smooth_files.py ``args`` in a Python where bpy cannot be imported (CompletedProcess)."""
    return subprocess.run(
        without_blender(args, script), cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env
    )


def obj_with_group(positions, faces, group="top"):
    """An OBJ with vertex normals whose faces on the upper half form group ``group``."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in positions.tolist()]
    radial = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in radial]
    upper = positions[faces].mean(axis=1)[:, 2] > 0
    for name, chosen in (("rest", ~upper), (group, upper)):
        lines.append(f"g {name}")
        lines += ["f " + " ".join(f"{v + 1}//{v + 1}" for v in face) for face in faces[chosen]]
    return ("\n".join(lines) + "\n").encode()


def stl_binary(positions, faces):
    records = np.zeros(len(faces), dtype=[("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
    records["corners"] = positions[faces]
    return b"binary STL from a scanner".ljust(80, b" ") + np.uint32(len(faces)).tobytes() + records.tobytes()


def scan_folder(folder, subdivisions=3):
    """``folder`` with a mesh in every format the route reads: rich ASCII and binary PLY (normals, colours,
    extra elements), an OBJ with normals and a group "top", a binary STL; returns it."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "rich.ply").write_bytes(scan_files.rich_ply("ascii")[0])
    (folder / "binary.ply").write_bytes(scan_files.rich_ply("binary_little_endian", seed=1)[0])
    positions, faces = scan_files.octahedron(noise=0.02, seed=2, subdivisions=subdivisions)
    (folder / "grouped.obj").write_bytes(obj_with_group(positions, faces))
    positions, faces = scan_files.octahedron(noise=0.02, seed=3, subdivisions=subdivisions)
    (folder / "part.stl").write_bytes(stl_binary(positions, faces))
    return folder


def cloud_folder(folder, count=600, seed=4):
    """``folder`` with one point cloud (a PLY of noisy points on a sphere, no faces); returns it."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(count, 3))
    points = points / np.linalg.norm(points, axis=1, keepdims=True) + 0.01 * rng.normal(size=(count, 3))
    vertex = [("x", "float"), ("y", "float"), ("z", "float")]
    (folder / "cloud.ply").write_bytes(scan_files.ply([("vertex", vertex, points.tolist())], "binary_little_endian"))
    return folder


# Option sets the comparisons run: (folder kind, options).
OPTION_SETS = (
    ("meshes", ()),
    ("meshes", ("--method", "LAPLACIAN", "--iterations", "5", "--format", "obj")),
    ("meshes", ("--keep-sharp-edges", "--format", "ply", "--deviation-attribute")),
    ("meshes", ("--fixed-group", "top", "--iterations", "8", "--mode", "SEQUENTIAL", "--slide")),
    ("points", ("--points",)),
)


def inputs_for(kind, folder, options):
    """The inputs of an option set: a folder of meshes (the OBJ alone with --fixed-group), or of clouds."""
    if kind == "points":
        return [cloud_folder(folder)]
    scan_folder(folder)
    return [pathlib.Path(folder) / "grouped.obj"] if "--fixed-group" in options else [folder]
