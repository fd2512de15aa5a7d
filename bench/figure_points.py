"""The point-cloud figure of docs/point_clouds.md (docs/images/point_clouds.png): a real scan sampled to points,
Gaussian noise, then CGAL jet smoothing and HC Smooth (core.smooth_point_cloud at its defaults), each
cloud coloured by its distance to the clean surface on one shared scale.

    .envs/bench/bin/python -m bench.figure_points                 # the figure of docs/point_clouds.md
    .envs/bench/bin/python -m bench.figure_points --object cow --sigma 0.01 --output /tmp/cow.png

(from the repository's folder: ``-m`` finds bench/ there).

Input: the pymeshlab wheel's Stanford bunny (a closed scan), area-uniform samples (bench_quality_inputs.py),
noise along the normals. Prints RMS / mean signed / max distance to the clean surface for each cloud.
Needs the bench environment (bench/requirements.txt: trimesh, Open3D, CGAL, matplotlib, Pillow).
"""

import argparse
import io
import pathlib

import numpy as np
from scipy.spatial import cKDTree

from bench import bench_points
from bench import bench_quality_inputs as inputs
from bench.common import ROOT

BACKGROUND = "#3b3c41"  # the mesh figure's (demo/scene_setup.py) background, for a matching pair
LIGHT = np.array([-0.45, 0.55, 0.70])  # towards the viewer, from the upper left


def signed_distance(vertices, faces, points):
    """Distance to the closed clean mesh, negative inside (Open3D's BVH)."""
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(np.ascontiguousarray(vertices, np.float32)),
        o3d.core.Tensor(np.ascontiguousarray(faces, np.uint32)),
    )
    query = o3d.core.Tensor(np.ascontiguousarray(points, np.float32))
    return scene.compute_signed_distance(query).numpy().astype(np.float64)


def view_rotation(azimuth, elevation):
    """Rows: screen right, screen up, towards the viewer; for a view around the object's +Y axis."""
    a, e = np.radians(azimuth), np.radians(elevation)
    towards = np.array([np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)])
    right = np.cross([0.0, 1.0, 0.0], towards)
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(towards, right), towards])


def shading(points, towards, k=16):
    """Lambert shading from normals fitted to each point's k nearest neighbours of the same cloud (so
    a rough cloud looks rough), turned towards the viewer."""
    _, neighbours = cKDTree(points).query(points, k)
    local = points[neighbours] - points[neighbours].mean(axis=1, keepdims=True)
    normals = np.linalg.eigh(np.einsum("nki,nkj->nij", local, local))[1][:, :, 0]
    normals *= np.where(normals @ towards < 0, -1.0, 1.0)[:, None]
    return np.clip(normals @ (LIGHT / np.linalg.norm(LIGHT)), 0.0, 1.0)


def draw_cloud(ax, points, colours, rotation, centre, spacing, pixels_per_unit, dpi):
    """Points as discs, far ones first, in an orthographic view."""
    screen = (points - centre) @ rotation.T
    order = np.argsort(screen[:, 2])
    # In points; 3 spacings: discs that close an evenly spread sample, so a gap shows points that left it.
    diameter = 3.0 * spacing * pixels_per_unit * 72 / dpi
    ax.scatter(
        screen[order, 0], screen[order, 1], s=diameter**2, c=colours[order], marker="o", linewidths=0, rasterized=True
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="bunny", help=f"one of {', '.join(inputs.ALL_MESHES)}")
    parser.add_argument("--points", type=int, default=50_000)
    parser.add_argument("--sigma", type=float, default=0.005, help="noise σ, fraction of the bbox diagonal")
    parser.add_argument("--kind", default="normal", help="noise along the normals ('normal') or 'iso'")
    parser.add_argument("--limit", type=float, default=1.0, help="top of the colour scale, in %% of the diagonal")
    parser.add_argument("--view", default="-30,15", help="azimuth,elevation in degrees")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--output", default=str(ROOT / "docs" / "images" / "point_clouds.png"))
    args = parser.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize
    from PIL import Image

    vertices, faces = inputs.load_mesh(args.object)
    clean, normals = inputs.sample_surface(vertices, faces, args.points, args.seed)
    diagonal = inputs.diagonal(clean)
    noisy = inputs.add_noise(clean, normals, args.sigma * diagonal, args.kind, args.seed + 1)
    jet, jet_seconds = bench_points.cgal_jet(noisy)
    ours, ours_seconds, note = bench_points.hc_rfs(noisy)
    along = "along the normals" if args.kind == "normal" else "on every coordinate"
    clouds = [
        ("Noisy", f"σ = {100 * args.sigma:.2g} % of the diagonal, {along}", noisy, None),
        ("CGAL jet smoothing", "k = 24 neighbours", jet, jet_seconds),
        ("HC Smooth", "defaults (automatic amount)", ours, ours_seconds),
    ]

    print(
        f"{args.object}: {args.points} points, noise σ = {args.sigma:.2%} of the diagonal ({args.kind}), seed "
        f"{args.seed}; HC Smooth's automatic amount: {note}"
    )
    print(f"{'':<20} {'RMS distance':>12} {'mean (signed)':>13} {'max distance':>12} {'noise removed':>13} {'time':>7}")
    distances = []
    for name, _, points, seconds in clouds:
        signed = signed_distance(vertices, faces, points)
        distances.append(signed)
        rms = float(np.sqrt(np.mean(signed**2)))
        removed = "" if seconds is None else f"{1 - rms / np.sqrt(np.mean(distances[0] ** 2)):.0%}"
        print(
            f"{name:<20} {100 * rms / diagonal:>10.3f} % {100 * signed.mean() / diagonal:>+11.3f} % "
            f"{100 * np.abs(signed).max() / diagonal:>10.3f} % {removed:>13} "
            f"{'' if seconds is None else f'{seconds:.1f} s':>7}"
        )
    print("distances to the clean surface in % of the bounding-box diagonal; mean signed: negative = inside")

    rotation = view_rotation(*(float(v) for v in args.view.split(",")))
    centre = (clean.max(axis=0) + clean.min(axis=0)) / 2
    screen = (clean - centre) @ rotation.T
    half = np.abs(screen[:, :2]).max(axis=0) * 1.08
    dpi, panel_px = 100, 520
    pixels_per_unit = panel_px / (2 * half[0])
    area = float(
        np.linalg.norm(
            np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]]),
            axis=1,
        ).sum()
        / 2
    )
    spacing = np.sqrt(area / args.points)
    # White on the surface, deepening red away from it: unsigned, since in any view the points in front
    # (pushed outwards) hide those pushed inwards, and a signed map would show only the first.
    colour_map, norm = plt.get_cmap("Reds"), Normalize(0.0, args.limit)

    panel_height = panel_px * half[1] / half[0]
    height = panel_height + 250
    figure = plt.figure(figsize=(3 * panel_px / dpi, height / dpi), dpi=dpi, facecolor=BACKGROUND)
    top, bottom = 1 - 60 / height, 190 / height
    for index, ((name, detail, points, _), signed) in enumerate(zip(clouds, distances, strict=True)):
        ax = figure.add_axes((index / 3, bottom, 1 / 3, top - bottom))
        ax.set_facecolor(BACKGROUND)
        ax.set_xlim(-half[0], half[0])
        ax.set_ylim(-half[1], half[1])
        ax.set_aspect("equal")
        ax.axis("off")
        colours = colour_map(norm(100 * np.abs(signed) / diagonal))[:, :3]
        colours *= (0.35 + 0.65 * shading(points, rotation[2]))[:, None]
        draw_cloud(ax, points, colours, rotation, centre, spacing, pixels_per_unit, dpi)
        rms = np.sqrt(np.mean(signed**2))
        result = f"RMS distance {100 * rms / diagonal:.2f} %"
        if index:
            result += f", {100 * (1 - rms / np.sqrt(np.mean(distances[0] ** 2))):.0f} % of the noise removed"
        figure.text(
            (index + 0.5) / 3,
            top + 8 / height,
            f"{name}\n{detail}",
            ha="center",
            va="bottom",
            color="white",
            fontsize=13,
            linespacing=1.4,
        )
        figure.text((index + 0.5) / 3, bottom - 8 / height, result, ha="center", va="top", color="white", fontsize=13)
    bar_bottom, bar_height = 55 / height, 16 / height
    bar = figure.add_axes((0.35, bar_bottom, 0.3, bar_height))
    colourbar = figure.colorbar(plt.cm.ScalarMappable(norm, colour_map), cax=bar, orientation="horizontal")
    ticks = np.linspace(0.0, args.limit, 5)
    colourbar.set_ticks(ticks)
    colourbar.ax.set_xticklabels(
        [f"{v:.2g} %" if v else "0" for v in ticks[:-1]] + [f"≥ {args.limit:.2g} %"], color="white", fontsize=11
    )
    colourbar.outline.set_visible(False)
    bar.tick_params(colors="white")
    figure.text(
        0.5,
        bar_bottom + bar_height + 10 / height,
        f"distance to the clean surface, % of the bounding-box diagonal ({args.object} scan from the "
        f"pymeshlab wheel, {args.points:,} points)",
        ha="center",
        va="bottom",
        color="white",
        fontsize=11,
    )

    buffer = io.BytesIO()
    figure.savefig(buffer, dpi=dpi, facecolor=BACKGROUND)
    # 256 colours keep the PNG small: 192 chosen for the picture, 64 exact steps of the colour bar.
    image = Image.open(buffer).convert("RGB")
    chosen = image.quantize(192, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).getpalette()[: 192 * 3]
    steps = np.round(255 * colour_map(np.linspace(0.0, 1.0, 64))[:, :3]).astype(int).ravel().tolist()
    palette = Image.new("P", (1, 1))
    palette.putpalette(chosen + steps)
    image = image.quantize(palette=palette, dither=Image.Dither.NONE)
    output = pathlib.Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    image.save(output, optimize=True)
    print(f"figure: {output} ({output.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
