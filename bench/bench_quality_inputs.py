"""Inputs and measures shared by the quality benchmarks (bench_quality.py for meshes,
bench_quality_points.py for point clouds): real scanned meshes with a clean reference, generated
shapes with thin parts and sharp edges, seeded noise, and distances to the clean surface.

Real data: the sample meshes inside the pymeshlab wheel (bunny.obj, a closed 28k-vertex scan; cow.obj,
with legs, ears and horns; bone.ply; airplane.obj, with thin wings) and Blender's Suzanne, subdivided
twice (open: its eyes are separate parts with holes behind them), exported once through the bpy module
of .envs/bpy45 and cached in bench/results/. Generated: a cube (sharp edges and corners), a thin
plate (sharp edges, 4 % as thick as wide) and a thin torus (tube radius 1/12 of the ring's).

These eight are the TUNING set: the Automatic Amount was tuned on them. The HELD_OUT set is real scans
it never saw, open ones among them (their borders count in every measure):

* face: a raw range scan from the pymeshlab wheel (rangemaps/face000.ply; 85,182 vertices, 20 parts,
  holes and a ragged border);
* scan_bunny: the Stanford bunny as pymeshfix ships it to be repaired (examples/StanfordBunny.ply;
  50,000 vertices, open, holes in the base, 132 non-manifold edges);
* planar_scan: pymeshfix's examples/planar_mesh.ply (1,403 vertices, a nearly flat open patch with
  holes, a fifth of its vertices on a border);
* bunny10k: the bunny of the pymeshlab wheel in another tessellation (bunny10k_textured.obj; 5,051
  vertices, open): the same shape as the tuning bunny, so it tests a new tessellation, not a new shape;
* armadillo and dragon: the Stanford Armadillo (26,002 vertices, closed) and the Chinese Dragon scan
  (ChineseDragon-10kv.off; 10,000 vertices, one small hole) of CGAL's data, which Debian's
  libcgal-demo package ships (read from its installed data.tar.gz, else from the package fetched with
  ``apt-get download libcgal-demo``; cached in bench/results/).

The pymeshlab wheel's colored_airplane.ply is the tuning airplane vertex for vertex, so it is not used.

Benchmark tools only: trimesh loads the files and Open3D measures distances (bench/requirements.txt).
"""

import io
import pathlib
import subprocess
import tarfile
import tempfile

import numpy as np

from bench import meshes
from bench.common import ROOT
from bench.report import RESULTS

BPY45 = ROOT / ".envs" / "bpy45" / "bin" / "python"

REAL = {"bunny": "bunny.obj", "cow": "cow.obj", "bone": "bone.ply", "airplane": "airplane.obj"}
GENERATED = ("cube", "plate", "thin_torus")
ALL_MESHES = ("bunny", "cow", "bone", "airplane", "suzanne") + GENERATED
TUNING = ALL_MESHES
# Held-out real scans: (package, path inside it) of the file.
SCANS = {
    "face": ("pymeshlab", "tests/sample_meshes/rangemaps/face000.ply"),
    "scan_bunny": ("pymeshfix", "examples/StanfordBunny.ply"),
    "planar_scan": ("pymeshfix", "examples/planar_mesh.ply"),
    "bunny10k": ("pymeshlab", "tests/sample_meshes/bunny10k_textured.obj"),
    "armadillo": ("libcgal-demo", "data/meshes/armadillo.off"),
    "dragon": ("libcgal-demo", "data/meshes/ChineseDragon-10kv.off"),
}
HELD_OUT = tuple(SCANS)
SETS = {"tuning": TUNING, "heldout": HELD_OUT}
CGAL_DATA = pathlib.Path("/usr/share/doc/libcgal-dev/data.tar.gz")  # where libcgal-demo installs it


def pymeshlab_samples():
    import pymeshlab

    return pathlib.Path(pymeshlab.__file__).resolve().parent / "tests" / "sample_meshes"


def _load_file(path, file_type=None):
    """(vertices, faces) of a triangle mesh file (a path, or an open file with ``file_type``),
    coincident vertices merged (OBJ/PLY seams split them)."""
    import trimesh

    if file_type is None:
        mesh = trimesh.load(str(path), process=False, force="mesh")
    else:
        mesh = trimesh.load(path, file_type=file_type, process=False, force="mesh")
    mesh = trimesh.Trimesh(
        np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64), process=True, validate=False
    )
    return np.asarray(mesh.vertices, np.float64).copy(), np.asarray(mesh.faces, np.int64).copy()


SUZANNE_SCRIPT = """
import sys, bpy, numpy as np
bpy.ops.wm.read_homefile(use_empty=True)
bpy.ops.mesh.primitive_monkey_add()
obj = bpy.context.active_object
sub = obj.modifiers.new("subdivision", "SUBSURF")
sub.levels = sub.render_levels = 2
obj.modifiers.new("triangulate", "TRIANGULATE")
mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
v = np.empty(len(mesh.vertices) * 3); mesh.vertices.foreach_get("co", v)
mesh.calc_loop_triangles()
f = np.empty(len(mesh.loop_triangles) * 3, np.int64); mesh.loop_triangles.foreach_get("vertices", f)
np.savez(sys.argv[1], vertices=v.reshape(-1, 3), faces=f.reshape(-1, 3))
"""


def suzanne():
    """Blender's Suzanne, Catmull-Clark subdivided twice and triangulated (7958 vertices, open)."""
    cache = RESULTS / "suzanne_subdivided2.npz"
    if not cache.exists():
        if not BPY45.exists():
            raise FileNotFoundError(f"Suzanne comes from Blender's bpy module: {BPY45} is missing")
        RESULTS.mkdir(exist_ok=True)
        subprocess.run([str(BPY45), "-c", SUZANNE_SCRIPT, str(cache)], check=True, capture_output=True, timeout=300)
    data = np.load(cache)
    return data["vertices"].astype(np.float64), data["faces"].astype(np.int64)


def _cgal_data(member):
    """The bytes of ``member`` of CGAL's data archive (Debian's libcgal-demo package)."""
    if CGAL_DATA.exists():
        with tarfile.open(CGAL_DATA) as archive:
            return archive.extractfile(member).read()
    with tempfile.TemporaryDirectory() as folder:
        subprocess.run(["apt-get", "download", "libcgal-demo"], cwd=folder, check=True, capture_output=True)
        package = next(pathlib.Path(folder).glob("libcgal-demo_*.deb"))
        subprocess.run(["dpkg-deb", "-x", str(package), folder], check=True)
        with tarfile.open(pathlib.Path(folder) / CGAL_DATA.relative_to("/")) as archive:
            return archive.extractfile(member).read()


def scan(name):
    """(vertices, faces) of a held-out scan (SCANS); CGAL's are cached in bench/results/."""
    package, member = SCANS[name]
    if package != "libcgal-demo":
        root = pathlib.Path(__import__(package).__file__).resolve().parent
        return _load_file(root / member)
    cache = RESULTS / f"cgal_{pathlib.Path(member).stem}.npz"
    if not cache.exists():
        vertices, faces = _load_file(io.BytesIO(_cgal_data(member)), file_type=pathlib.Path(member).suffix[1:])
        RESULTS.mkdir(exist_ok=True)
        np.savez(cache, vertices=vertices, faces=faces)
    data = np.load(cache)
    return data["vertices"].astype(np.float64), data["faces"].astype(np.int64)


def box(dimensions, spacing):
    """A closed box centred on the origin, each side a regular grid of about ``spacing``, triangulated,
    faces outward, vertices shared along the edges (sharp edges and corners)."""
    cells = np.maximum(1, np.round(np.asarray(dimensions, float) / spacing).astype(int))
    points, triangles = [], []
    offset = 0
    for axis in range(3):
        u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3  # u x v = +axis
        nu, nv = cells[u_axis], cells[v_axis]
        iu, iv = np.meshgrid(np.arange(nu + 1), np.arange(nv + 1), indexing="ij")
        for side in (0, 1):
            lattice = np.zeros((iu.size, 3), np.int64)
            lattice[:, u_axis], lattice[:, v_axis] = iu.ravel(), iv.ravel()
            lattice[:, axis] = side * cells[axis]
            a = (iu[:-1, :-1] * (nv + 1) + iv[:-1, :-1]).ravel()
            b, c, d = a + (nv + 1), a + (nv + 1) + 1, a + 1
            quads = np.stack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)], 1).reshape(-1, 3)
            if side == 0:
                quads = quads[:, ::-1]
            points.append(lattice)
            triangles.append(quads + offset)
            offset += len(lattice)
    lattice = np.concatenate(points)
    unique, inverse = np.unique(lattice, axis=0, return_inverse=True)
    faces = inverse.reshape(-1)[np.concatenate(triangles)]
    vertices = unique * (np.asarray(dimensions, float) / cells) - np.asarray(dimensions, float) / 2
    return vertices, faces.astype(np.int64)


def load_mesh(name):
    """(vertices, faces) of a benchmark mesh, faces outward where it is closed."""
    if name in REAL:
        vertices, faces = _load_file(pymeshlab_samples() / REAL[name])
    elif name == "suzanne":
        vertices, faces = suzanne()
    elif name == "cube":
        vertices, faces = box((2.0, 2.0, 2.0), 2.0 / 32)
    elif name == "plate":
        vertices, faces = box((2.0, 2.0, 0.08), 0.04)
    elif name == "thin_torus":
        vertices, faces = meshes.torus(4000, ratio=12.0, minor_radius=0.08)
    elif name in SCANS:
        vertices, faces = scan(name)
    else:
        raise ValueError(f"unknown mesh {name!r}; known: {', '.join(TUNING + HELD_OUT)}")
    if is_closed(faces) and signed_volume(vertices, faces) < 0:
        faces = faces[:, ::-1].copy()
    return vertices, faces


# --- measures -----------------------------------------------------------------------------------------


def is_closed(faces):
    """Every edge has exactly two faces."""
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(pairs, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def signed_volume(vertices, faces):
    centre = vertices.mean(axis=0)
    a, b, c = (vertices[faces[:, k]] - centre for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def diagonal(vertices):
    return float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))


def mean_edge_length(vertices, faces):
    edges = meshes.edges_from_faces(faces)
    return float(np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1).mean())


def vertex_normals(vertices, faces):
    """Area-weighted unit vertex normals."""
    face_normals = np.cross(
        vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]]
    )
    normals = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(normals, faces[:, k], face_normals)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0, length, 1.0)


def add_noise(points, normals, sigma, kind, seed):
    """Gaussian noise of standard deviation ``sigma``: ``"normal"`` along the unit ``normals`` (one number
    per point), ``"iso"`` on every coordinate."""
    rng = np.random.default_rng(seed)
    if kind == "normal":
        return points + normals * rng.normal(0.0, sigma, (len(points), 1))
    if kind == "iso":
        return points + rng.normal(0.0, sigma, points.shape)
    raise ValueError(f"noise kind {kind!r}: 'normal' or 'iso'")


class Surface:
    """Unsigned distance to a clean triangle mesh (Open3D's BVH)."""

    def __init__(self, vertices, faces):
        import open3d as o3d

        self._o3d = o3d
        self.scene = o3d.t.geometry.RaycastingScene()
        self.scene.add_triangles(
            o3d.core.Tensor(np.ascontiguousarray(vertices, np.float32)),
            o3d.core.Tensor(np.ascontiguousarray(faces, np.uint32)),
        )

    def distance(self, points):
        query = self._o3d.core.Tensor(np.ascontiguousarray(points, np.float32))
        return self.scene.compute_distance(query).numpy().astype(np.float64)


def sample_surface(vertices, faces, count, seed):
    """``count`` area-uniform points on the mesh and the unit normal of the face each lies on."""
    rng = np.random.default_rng(seed)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    cross = np.cross(b - a, c - a)
    area = np.linalg.norm(cross, axis=1)
    chosen = rng.choice(len(faces), size=count, p=area / area.sum())
    r1, r2 = rng.random((2, count, 1))
    flip = (r1 + r2) > 1
    r1, r2 = np.where(flip, 1 - r1, r1), np.where(flip, 1 - r2, r2)
    points = a[chosen] + r1 * (b[chosen] - a[chosen]) + r2 * (c[chosen] - a[chosen])
    return points, cross[chosen] / area[chosen, None]


def parse_list(text, kind=str):
    return [kind(item.strip()) for item in text.split(",") if item.strip()]
