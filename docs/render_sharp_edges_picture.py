"""Render docs/images/sharp_edges.png: a noisy machined part (a cylinder with a through hole) smoothed by
HC Smooth's default, by Keep Sharp Edges (Automatic Amount) and by MeshLab's two-step smoothing at its
defaults, coloured by the signed distance to the clean part on one scale (Cycles, headless bpy).

    .envs/bpy45/bin/python docs/render_sharp_edges_picture.py [--output docs/images/sharp_edges.png]

MeshLab runs in the benchmark environment (``--peer-python``, default .envs/bench/bin/python, which has
pymeshlab): the script runs itself there with ``--smooth FILE`` to write the four meshes' positions, then
renders them with the demo's scene, colour map and legend (demo/scene_setup.py).
"""

import argparse
import math
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "scripts"), str(ROOT / "demo"), str(ROOT)]

NOISE = 0.005  # of the bounding-box diagonal, along the normals
COLOUR_LIMIT = 0.5  # % of the diagonal at the ends of the colour scale
SEED = 11
TILT = math.radians(55.0)  # the part's top turned towards the camera


def smooth(path):
    """The clean part, its noisy copy and the three results, written to ``path`` (.npz)."""
    import core
    from bench import bench_quality as quality
    from bench import bench_quality_inputs as inputs
    from bench import sharp_parts

    clean, faces = sharp_parts.holed_cylinder()
    clean = clean - (clean.max(axis=0) + clean.min(axis=0)) / 2
    diagonal = inputs.diagonal(clean)
    normals = inputs.vertex_normals(clean, faces)
    noisy = inputs.add_noise(clean, normals, NOISE * diagonal, "normal", SEED)
    case = quality.Case("holed_cylinder", "normal", NOISE, clean, faces, noisy)
    hc = core.smooth_mesh(noisy, case.edges, faces=faces, weld=True)
    ours = core.smooth_mesh(noisy, case.edges, faces=faces, weld=True, keep_sharp_edges=True)
    two_step = quality._meshlab(case, "apply_coord_two_steps_smoothing")
    np.savez(path, clean=clean, faces=faces, noisy=noisy, hc=hc, ours=ours, two_step=two_step)


def _crease_keys(points, faces, degrees=25.0):
    """Keys (low * n + high) of the edges whose two triangles meet at more than ``degrees``."""
    import core

    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keys = pairs[:, 0] * len(points) + pairs[:, 1]
    order = np.argsort(keys, kind="stable")
    keys, owner = keys[order], np.repeat(np.arange(len(faces)), 3)[order]
    shared = np.flatnonzero(keys[1:] == keys[:-1])
    normals = core.face_normals(points, faces)
    cosine = np.einsum("ij,ij->i", normals[owner[shared]], normals[owner[shared + 1]])
    return keys[shared][cosine < math.cos(math.radians(degrees))]


def render(arrays, output, samples):
    import bpy  # after extension_session (main): a throw-away Blender user folder
    import scene_setup

    import core

    bpy.ops.wm.read_homefile(use_empty=True)
    clean, faces = arrays["clean"], arrays["faces"]
    diagonal = float(np.linalg.norm(clean.max(axis=0) - clean.min(axis=0)))
    layout = (np.arange(len(faces) + 1) * 3, faces.ravel())
    surface = scene_setup.CleanSurface(clean, layout)
    clean_volume = core.enclosed_volume(clean, faces)
    creases = _crease_keys(clean, faces)
    panels = []
    titles = (
        ("noisy", f"Noisy, \u03c3 {NOISE:.1%}"),
        ("hc", "HC Smooth default"),
        ("ours", "Keep Sharp Edges"),
        ("two_step", "MeshLab two-step"),
    )
    for k, (key, title) in enumerate(titles):
        points = arrays[key]
        mesh = bpy.data.meshes.new(title)
        mesh.from_pydata(points.tolist(), [], faces.tolist())
        obj = scene_setup.object_from_mesh(mesh, title, (k * scene_setup.SPACING, 0.0, 0.0))
        obj.rotation_euler = (TILT, 0.0, 0.0)
        # The clean part's creases shade as edges (split normals) on every panel alike; elsewhere smooth.
        pairs = np.sort(scene_setup.edges(mesh), axis=1)
        sharp = np.isin(pairs[:, 0] * len(points) + pairs[:, 1], creases)
        mesh.attributes.new("sharp_edge", "BOOLEAN", "EDGE").data.foreach_set("value", sharp)
        signed = surface.signed_distance(points)
        scene_setup.set_point_attribute(obj, scene_setup.ERROR_ATTRIBUTE, 100 * signed / diagonal)
        volume = core.enclosed_volume(points, faces) / clean_volume - 1
        rms = 100 * float(np.sqrt(np.mean(signed**2))) / diagonal
        label = f"{title}\nvolume {100 * volume:+.2f} %\nRMS distance {rms:.3f} %"
        panels.append((obj, label))
        print(label.replace("\n", ", "))
    scene_setup.render_error_figure(
        panels,
        None,
        [],
        output,
        limit=COLOUR_LIMIT,
        samples=samples,
        resolution=(1400, 470),
        legend_title="signed distance to the clean part, % of the diagonal",
    )
    print(f"picture: {output}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(ROOT / "docs" / "images" / "sharp_edges.png"))
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--peer-python", default=str(ROOT / ".envs" / "bench" / "bin" / "python"))
    parser.add_argument("--smooth", help="write the meshes to this .npz and stop (runs in --peer-python)")
    args = parser.parse_args()
    if args.smooth:
        smooth(args.smooth)
        return
    with tempfile.TemporaryDirectory() as folder:
        path = str(pathlib.Path(folder) / "meshes.npz")
        subprocess.run([args.peer_python, __file__, "--smooth", path], check=True)
        arrays = dict(np.load(path))
    from extension_session import run_and_exit  # before bpy

    run_and_exit(lambda: render(arrays, args.output, args.samples))


if __name__ == "__main__":
    main()
