"""Does the Automatic Amount find noise where there is some, and only there? (core.mesh.noise)

For each mesh, clean and with Gaussian noise of 0.05, 0.1, 0.3 and 0.5 median edge lengths (along the
normals and isotropic, seed 0): whether noise was found (*), the robust estimate of core.mesh.noise
over the true noise and, where noise was found, the Automatic Amount's sigma (GCV's, which the
deviation limit uses) over the true noise. Clean meshes: the robust estimate in edge lengths, and the
largest move of a default run in % of the bounding-box diagonal.

Tuning set (the threshold and gain were chosen on these): Blender's primitives at their defaults
(bench/primitives.py, the same meshes as bpy's), Suzanne (Blender's Monkey, as it comes and
Catmull-Clark subdivided once and twice), CAD-like parts built in NumPy (a box with rounded or
chamfered edges, a tube). Held out: parts made in Blender (a cube with its edges bevelled by the Bevel
modifier, 1 and 3 segments; booleans: a disc with a hole, a cube with a hole, triangulated) and the
real meshes in the pymeshlab wheel (bunny scans at two resolutions, a bone, the cow and the airplane
models, a raw range map). Real scans carry their own noise: their "clean" cell is that noise.

    python bench/bench_noise_found.py [--meshes a,b,...]

Needs numpy, scipy, pymeshlab (bench/requirements.txt) and .envs/bpy45 for the Blender-made meshes
(made once, cached in bench/results/).
"""

import subprocess
import warnings

import numpy as np

import core
from bench import bench_quality_inputs as inputs
from bench import primitives
from bench.bench_quality_inputs import BPY45, pymeshlab_samples
from bench.common import Parameter
from bench.report import RESULTS

LEVELS = (0.05, 0.1, 0.3, 0.5)
SCANS = {
    "bunny": "bunny.obj",
    "bunny10k": "bunny10k_textured.obj",
    "bone": "bone.ply",
    "cow": "cow.obj",
    "airplane": "airplane.obj",
    "range_map": "rangemaps/face000.ply",
}
BLENDER_SCRIPT = """
import sys, bpy, numpy as np
def grab(name, obj, out):
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
    v = np.empty(len(mesh.vertices) * 3); mesh.vertices.foreach_get("co", v)
    sizes = np.empty(len(mesh.polygons), np.int64); mesh.polygons.foreach_get("loop_total", sizes)
    corners = np.empty(len(mesh.loops), np.int64); mesh.loops.foreach_get("vertex_index", corners)
    out[name + "_vertices"], out[name + "_sizes"], out[name + "_corners"] = v.reshape(-1, 3), sizes, corners
def clear():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
out = {}
bpy.ops.wm.read_homefile(use_empty=True)
for level in (0, 1, 2):
    bpy.ops.mesh.primitive_monkey_add(); obj = bpy.context.active_object
    if level:
        sub = obj.modifiers.new("s", "SUBSURF"); sub.levels = level
    grab(f"suzanne_{level}", obj, out); clear()
for segments in (1, 3):
    bpy.ops.mesh.primitive_cube_add(); obj = bpy.context.active_object
    bevel = obj.modifiers.new("b", "BEVEL"); bevel.width = 0.2; bevel.segments = segments
    grab(f"bevel_box_{segments}", obj, out); clear()
for name, outer, inner, triangulate in (("disc_hole", (64, 1.0, 0.5), (32, 0.4, 1.0), False),
                                         ("cube_hole", None, (32, 0.5, 3.0), True)):
    if outer:
        bpy.ops.mesh.primitive_cylinder_add(vertices=outer[0], radius=outer[1], depth=outer[2])
    else:
        bpy.ops.mesh.primitive_cube_add()
    a = bpy.context.active_object
    bpy.ops.mesh.primitive_cylinder_add(vertices=inner[0], radius=inner[1], depth=inner[2])
    b = bpy.context.active_object
    boolean = a.modifiers.new("bool", "BOOLEAN"); boolean.operation = "DIFFERENCE"; boolean.object = b
    boolean.solver = "EXACT"
    if triangulate:
        a.modifiers.new("t", "TRIANGULATE")
    grab(name, a, out); clear()
np.savez(sys.argv[1], **out)
"""
BLENDER_MESHES = ("suzanne_0", "suzanne_1", "suzanne_2", "bevel_box_1", "bevel_box_3", "disc_hole", "cube_hole")


def blender_meshes():
    cache = RESULTS / "noise_found_blender_meshes.npz"
    if not cache.exists():
        RESULTS.mkdir(exist_ok=True)
        subprocess.run([str(BPY45), "-c", BLENDER_SCRIPT, str(cache)], check=True, capture_output=True, timeout=600)
    data = np.load(cache)
    out = {}
    for name in BLENDER_MESHES:
        sizes, corners = data[name + "_sizes"], data[name + "_corners"]
        faces = np.split(corners, np.cumsum(sizes)[:-1])
        out[name] = primitives.mesh(data[name + "_vertices"], [list(face) for face in faces])
    return out


def scan(path):
    import pymeshlab

    meshes = pymeshlab.MeshSet()
    meshes.load_new_mesh(str(path))
    meshes.meshing_merge_close_vertices(threshold=pymeshlab.PercentageValue(0.0001))
    meshes.meshing_remove_unreferenced_vertices()
    mesh = meshes.current_mesh()
    return primitives.mesh(mesh.vertex_matrix().astype(np.float64), mesh.face_matrix().tolist())


def all_meshes(wanted=None):
    """(tuning, held out): name -> mesh, only those in ``wanted`` (None: all)."""

    def keep(names):
        return [name for name in names if wanted is None or name in wanted]

    tuning = {
        name: make() for name, make in {**primitives.PRIMITIVES, **primitives.CAD}.items() if name in keep([name])
    }
    held_out = {}
    if keep(BLENDER_MESHES):
        made = blender_meshes()
        tuning.update({name: made[name] for name in keep(("suzanne_0", "suzanne_1", "suzanne_2"))})
        held_out = {name: made[name] for name in keep(("bevel_box_1", "bevel_box_3", "disc_hole", "cube_hole"))}
    if keep(SCANS):
        samples = pymeshlab_samples()
        held_out.update({name: scan(samples / SCANS[name]) for name in keep(SCANS)})
    return tuning, held_out


def measure(part):
    """The row's cells for one mesh."""
    operator = core.umbrella_operator(part.edges, len(part.positions))
    edge = primitives.median_edge(part)
    noise = core.mesh.noise.find_noise(part.positions, operator)
    moved = 0.0
    if not noise.found:
        result = core.smooth_mesh(part.positions, part.edges, faces=part.faces or None)
        moved = np.linalg.norm(result - part.positions, axis=1).max() / np.linalg.norm(np.ptp(part.positions, axis=0))
    cells = [
        f"{noise.level() / edge:.3f}{'*' if noise.found else ''}",
        f"{100 * moved:.2g}" if not noise.found else "-",
    ]
    for kind in ("normal", "isotropic"):
        for ratio in LEVELS:
            noisy, sigma = primitives.with_noise(part, ratio, kind if part.faces else "isotropic")
            found = core.mesh.noise.find_noise(noisy.positions, operator)
            cell = f"{'*' if found.found else ''}{found.level() / sigma:.2f}"
            if found.found:
                amount = core.choose_amount(noisy.positions, operator=operator)
                cell += f" / {amount.sigma / sigma:.2f}"
            cells.append(cell)
    return cells


PARAMETERS = (Parameter("meshes", "", "comma-separated names (default: all)"),)
QUICK = {"meshes": "cube,cone_ngon"}


def run(args, out):
    warnings.simplefilter("ignore", core.ConvergenceWarning)
    wanted = set(inputs.parse_list(args.meshes)) or None
    tuning, held_out = all_meshes(wanted)
    header = ["mesh", "vertices", "clean: estimate / edge", "clean: moved % diag"]
    header += [f"{kind} {ratio}" for kind in ("normal", "iso") for ratio in LEVELS]
    out(f"* = noise found (threshold {core.mesh.noise.NOISE_THRESHOLD} edge lengths); noisy cells: robust")
    out("estimate / truth, and where found the Automatic Amount's sigma / truth.")
    for title, parts in (("Tuning set", tuning), ("Held-out set", held_out)):
        out(f"\n### {title}\n")
        table = out.table(*header)
        for name, part in parts.items():
            table.row(name, len(part.positions), *measure(part))
    return out.rows
