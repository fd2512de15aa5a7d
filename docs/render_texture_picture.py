"""Render docs/images/texture.png: a textured scan-like Suzanne, noisy, then smoothed by HC with the paper's
moves (vertices slide along the surface and the texture swims), by HC Smooth's default (Keep in Place) and by
MeshLab's Taubin smoothing at its defaults; close-ups of the same spot, same camera and lights (Cycles, headless
bpy), the clean mesh first as the reference.

    .envs/bpy45/bin/python docs/render_texture_picture.py [--output docs/images/texture.png]

(``--view X Z WIDTH`` and ``--panel PIXELS`` choose another close-up; about two minutes on two cores.)

The mesh: Blender's Suzanne with its holes capped, Catmull-Clark subdivided four times and decimated to a
quarter (an irregular triangulation, as a scanner's software leaves it; ~32k vertices), with Suzanne's own
UV map and a checker texture with bold labels drawn here with NumPy. Gaussian noise of NOISE times the
bounding-box diagonal moves each vertex along its clean normal, so the noisy mesh still carries the texture
where the clean one does. MeshLab runs in the benchmark environment (``--peer-python``, default
.envs/bench/bin/python, which has pymeshlab): the script runs itself there with ``--taubin FILE``.

For each result the script prints the *texture shift*: the RMS of each vertex's move from the noisy input
along the surface (its part across the clean vertex normal), in % of the bounding-box diagonal.
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

NOISE = 0.005  # of the bounding-box diagonal, along the clean normals
SEED = 5
LEVEL, RATIO = 4, 0.25  # Catmull-Clark levels, then the decimation ratio
VIEW = (-0.28, -0.4, 0.6)  # the close-up (her muzzle, left of the UV map's mirror seam): centre x, centre z and
# width, in Suzanne's units (she is 2.66 wide); there HC's slide is about as large as anywhere on her front
PANEL = 300  # pixels, each square panel
LABEL_HEIGHT = 58  # pixels, the label strip under the panels
GAP = 4  # pixels between the panels
TEXTURE = 2048  # pixels, the checker's side
CELLS = 16  # checker cells along each side of the texture

# --- the texture: a checker of labelled cells ---------------------------------------------------------------

_GLYPHS = {  # 5 x 7 bitmaps
    "A": "01110 10001 10001 11111 10001 10001 10001",
    "B": "11110 10001 10001 11110 10001 10001 11110",
    "C": "01110 10001 10000 10000 10000 10001 01110",
    "D": "11110 10001 10001 10001 10001 10001 11110",
    "E": "11111 10000 10000 11110 10000 10000 11111",
    "F": "11111 10000 10000 11110 10000 10000 10000",
    "G": "01110 10001 10000 10111 10001 10001 01111",
    "H": "10001 10001 10001 11111 10001 10001 10001",
    "I": "01110 00100 00100 00100 00100 00100 01110",
    "J": "00111 00010 00010 00010 00010 10010 01100",
    "K": "10001 10010 10100 11000 10100 10010 10001",
    "L": "10000 10000 10000 10000 10000 10000 11111",
    "M": "10001 11011 10101 10101 10001 10001 10001",
    "N": "10001 11001 10101 10011 10001 10001 10001",
    "O": "01110 10001 10001 10001 10001 10001 01110",
    "P": "11110 10001 10001 11110 10000 10000 10000",
    "0": "01110 10001 10011 10101 11001 10001 01110",
    "1": "00100 01100 00100 00100 00100 00100 01110",
    "2": "01110 10001 00001 00010 00100 01000 11111",
    "3": "11111 00010 00100 00010 00001 10001 01110",
    "4": "00010 00110 01010 10010 11111 00010 00010",
    "5": "11111 10000 11110 00001 00001 10001 01110",
    "6": "00110 01000 10000 11110 10001 10001 01110",
    "7": "11111 00001 00010 00100 01000 01000 01000",
    "8": "01110 10001 10001 01110 10001 10001 01110",
    "9": "01110 10001 10001 01111 00001 00010 01100",
}


def _glyph(char, scale):
    """The bitmap of ``char`` blown up ``scale`` times, its corners rounded (blurred, then cut at half)."""
    from scipy.ndimage import gaussian_filter

    bitmap = np.array([[c == "1" for c in row] for row in _GLYPHS[char].split()], dtype=float)
    big = np.pad(np.kron(bitmap, np.ones((scale, scale))), scale)
    return gaussian_filter(big, scale / 3) > 0.3  # bold


def checker_texture(size=TEXTURE, cells=CELLS):
    """(size, size, 4) floats in [0, 1], row 0 at the bottom (Blender's order): a checker of two colours,
    dark lines between the cells and a bold label (column letter, row number) in each cell."""
    light, tint, ink = np.array([0.95, 0.91, 0.80]), np.array([0.45, 0.66, 0.86]), np.array([0.08, 0.08, 0.10])
    cell = size // cells
    rows, columns = np.indices((size, size)) // cell
    image = np.where(((rows + columns) % 2 == 0)[..., None], light, tint)
    line = max(2, cell // 40)
    offset = np.indices((size, size)) % cell
    image[(offset[0] < line) | (offset[1] < line) | (offset[0] >= cell - line) | (offset[1] >= cell - line)] = ink
    scale = cell // 20  # a glyph is 5 x 7 units
    glyphs = {char: _glyph(char, scale) for char in _GLYPHS}
    for row in range(cells):
        for column in range(cells):
            text = f"{'ABCDEFGHIJKLMNOP'[column]}{row + 1}"
            width = (6 * len(text) - 1) * scale
            left = column * cell + (cell - width) // 2
            top = (cells - 1 - row) * cell + (cell - 7 * scale) // 2  # counted from the picture's top
            for k, char in enumerate(text):
                start = left + (6 * k - 1) * scale
                image[top - scale : top + 8 * scale, start : start + 7 * scale][glyphs[char]] = ink
    return np.concatenate([image[::-1], np.ones((size, size, 1))], axis=2)


# --- the numbers -------------------------------------------------------------------------------------------


def edges_of(triangles):
    return np.unique(np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)


def texture_shift(noisy, result, clean_normals, diagonal):
    """RMS of the moves from ``noisy`` to ``result`` across ``clean_normals`` (along the surface), % of the
    diagonal."""
    move = result - noisy
    along = move - np.einsum("ij,ij->i", move, clean_normals)[:, None] * clean_normals
    return 100 * float(np.sqrt(np.mean(np.einsum("ij,ij->i", along, along)))) / diagonal


def taubin(path):
    """MeshLab's Taubin smoothing at its defaults on the noisy mesh in ``path`` (.npz), added to it as ``taubin``."""
    import pymeshlab

    arrays = dict(np.load(path))
    meshset = pymeshlab.MeshSet()
    meshset.add_mesh(pymeshlab.Mesh(vertex_matrix=arrays["noisy"], face_matrix=arrays["triangles"].astype(np.int32)))
    meshset.apply_coord_taubin_smoothing()
    out = meshset.current_mesh().vertex_matrix()
    if out.shape != arrays["noisy"].shape:
        raise RuntimeError(f"MeshLab changed the vertex count ({len(arrays['noisy'])} -> {len(out)})")
    np.savez(path, **arrays, taubin=out)


# --- Blender ------------------------------------------------------------------------------------------------


def clean_suzanne():
    """(positions, triangles, per-corner UVs) of the clean scan-like Suzanne."""
    import bpy
    import scene_setup

    obj = scene_setup.closed_suzanne(level=LEVEL)
    scene_setup.select_only(obj)
    decimate = obj.modifiers.new("Decimate", "DECIMATE")
    decimate.ratio = RATIO
    bpy.ops.object.modifier_apply(modifier=decimate.name)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.quads_convert_to_tris(quad_method="BEAUTY", ngon_method="BEAUTY")
    bpy.ops.object.mode_set(mode="OBJECT")
    mesh = obj.data
    points = scene_setup.positions(mesh).astype(np.float64)
    _, corners = scene_setup.faces(mesh)
    uvs = np.empty(len(mesh.loops) * 2, dtype=np.float32)
    mesh.uv_layers.active.data.foreach_get("uv", uvs)
    bpy.data.objects.remove(obj)
    return points, corners.reshape(-1, 3), uvs.reshape(-1, 2)


def textured_material():
    import bpy

    image = bpy.data.images.new("Checker", TEXTURE, TEXTURE, alpha=False)
    image.pixels.foreach_set(checker_texture().astype(np.float32).ravel())
    image.pack()
    material = bpy.data.materials.new("Checker")
    material.use_nodes = True
    tree = material.node_tree
    shader = tree.nodes["Principled BSDF"]
    shader.inputs["Roughness"].default_value = 0.6
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Cubic"
    tree.links.new(texture.outputs["Color"], shader.inputs["Base Color"])
    return material


def _mesh_object(name, points, triangles, uvs, material):
    import bpy

    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(points.tolist(), [], triangles.tolist())
    mesh.uv_layers.new(name="UVMap").data.foreach_set("uv", uvs.ravel())
    mesh.polygons.foreach_set("use_smooth", np.ones(len(triangles), dtype=bool))
    mesh.materials.append(material)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _scene(samples):
    """The figures' look (demo/scene_setup.figure_scene), no stamps."""
    import scene_setup

    scene = scene_setup.figure_scene(samples)
    scene.render.use_stamp = False
    return scene


def _camera(scene, x, z, width, resolution):
    import bpy

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = width
    camera.location = (x, -10.0, z)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)  # looking along +Y, at Suzanne's face
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    return camera


def _render(scene, path):
    """Render to ``path`` and return its pixels, (height, width, 3) in [0, 1], top row first."""
    import bpy

    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(path))
    pixels = np.empty(image.size[0] * image.size[1] * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(image.size[1], image.size[0], image.channels)[::-1, :, :3]
    bpy.data.images.remove(image)
    return pixels


def write_png(path, picture):
    """Write (height, width, 3) floats in [0, 1] as an 8-bit RGB PNG, each row with the filter (none, sub, up,
    average, Paeth) of the smallest sum of absolute residues, as libpng chooses: a smaller file than
    Blender's own writer."""
    import struct
    import zlib

    rgb = np.round(np.clip(picture, 0.0, 1.0) * 255).astype(np.int16)
    height, width = rgb.shape[:2]
    rows = rgb.reshape(height, width * 3)
    above = np.vstack([np.zeros((1, width * 3), np.int16), rows[:-1]])
    left = np.hstack([np.zeros((height, 3), np.int16), rows[:, :-3]])
    corner = np.hstack([np.zeros((height, 3), np.int16), above[:, :-3]])
    estimate = left + above - corner
    distance = [np.abs(estimate - left), np.abs(estimate - above), np.abs(estimate - corner)]
    paeth = np.where(
        (distance[0] <= distance[1]) & (distance[0] <= distance[2]),
        left,
        np.where(distance[1] <= distance[2], above, corner),
    )
    residues = [rows, rows - left, rows - above, rows - (left + above) // 2, rows - paeth]
    residues = np.stack([(r % 256).astype(np.uint8) for r in residues])
    cost = np.abs(residues.astype(np.int8).astype(np.int16)).sum(axis=2)
    choice = cost.argmin(axis=0)
    body = np.hstack([choice[:, None].astype(np.uint8), residues[choice, np.arange(height)]]).tobytes()

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(body, 9)) + chunk(b"IEND", b"")
    pathlib.Path(path).write_bytes(data)


def meshes(peer_python):
    """(arrays, titles): the clean, noisy and smoothed positions with the triangles and UVs, and each panel's
    (key, label), the label with the texture shift, which is also printed."""
    import core

    clean, triangles, uvs = clean_suzanne()
    diagonal = float(np.linalg.norm(clean.max(axis=0) - clean.min(axis=0)))
    normals = core.vertex_normals(clean, triangles)
    noisy = clean + normals * np.random.default_rng(SEED).normal(0.0, NOISE * diagonal, (len(clean), 1))
    edges = edges_of(triangles)
    sliding = core.smooth_mesh(noisy, edges, faces=triangles, weld=True, keep_in_place=False)
    kept = core.smooth_mesh(noisy, edges, faces=triangles, weld=True)
    with tempfile.TemporaryDirectory() as folder:
        path = str(pathlib.Path(folder) / "meshes.npz")
        np.savez(path, noisy=noisy, triangles=triangles)
        subprocess.run([peer_python, __file__, "--taubin", path], check=True)
        meshlab = np.load(path)["taubin"]
    arrays = dict(clean=clean, noisy=noisy, sliding=sliding, kept=kept, taubin=meshlab, triangles=triangles, uvs=uvs)
    print(f"{len(clean)} vertices, {len(triangles)} triangles, noise {NOISE:.1%} of the diagonal along the normals")
    titles = [("clean", "Clean (reference)"), ("noisy", f"Noisy, \u03c3 {100 * NOISE:.1f} %\n(along the normals)")]
    for key, title in (
        ("sliding", "HC, sliding (paper's moves)"),
        ("kept", "HC Smooth default (Keep in Place)"),
        ("taubin", "MeshLab Taubin (defaults)"),
    ):
        shift = texture_shift(noisy, arrays[key], normals, diagonal)
        print(f"{title}: texture shift {shift:.3f} % of the diagonal (RMS)")
        titles.append((key, f"{title}\ntexture shift {shift:.2f} %"))
    return arrays, titles


def render(arrays, titles, output, samples, view, panel):
    import bpy
    import scene_setup

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = _scene(samples)
    material = textured_material()
    objects = [_mesh_object(title, arrays[key], arrays["triangles"], arrays["uvs"], material) for key, title in titles]
    x, z, width = view
    camera = _camera(scene, x, z, width, (panel, panel))
    panels = []
    with tempfile.TemporaryDirectory() as folder:
        for k, obj in enumerate(objects):
            for other in objects:
                other.hide_render = other is not obj
            panels.append(_render(scene, pathlib.Path(folder) / f"panel{k}.png"))
        # The labels: white text on the background, one strip under all panels, measured in pixels.
        for obj in objects:
            obj.hide_render = True
        label = scene_setup._material("Label", emission=(0.92, 0.92, 0.92))
        far = 1000.0  # the strip stands away from Suzanne, one scene unit a pixel
        for k, (_, title) in enumerate(titles):
            scene_setup._text(title, (far + (k + 0.5) * (panel + GAP), 0.0, far - 8), 19, label)
        bpy.data.objects.remove(camera)
        width_px = len(titles) * (panel + GAP) - GAP
        _camera(scene, far + width_px / 2, far - LABEL_HEIGHT / 2, width_px, (width_px, LABEL_HEIGHT))
        scene.cycles.samples = 4
        strip = _render(scene, pathlib.Path(folder) / "labels.png")
    gap = np.full((panel, GAP, 3), strip[0, 0])
    row = np.concatenate([part for image in panels for part in (image, gap)][:-1], axis=1)
    write_png(output, np.concatenate([row, strip], axis=0))
    print(f"picture: {output}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(ROOT / "docs" / "images" / "texture.png"))
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--view", type=float, nargs=3, default=VIEW, metavar=("X", "Z", "WIDTH"), help="the close-up")
    parser.add_argument("--panel", type=int, default=PANEL, help="pixels, each panel's side")
    parser.add_argument("--peer-python", default=str(ROOT / ".envs" / "bench" / "bin" / "python"))
    parser.add_argument("--taubin", help="add MeshLab's Taubin result to this .npz and stop (runs in --peer-python)")
    args = parser.parse_args()
    if args.taubin:
        taubin(args.taubin)
        return

    from extension_session import run_and_exit  # before bpy

    run_and_exit(lambda: render(*meshes(args.peer_python), args.output, args.samples, args.view, args.panel))


if __name__ == "__main__":
    main()
