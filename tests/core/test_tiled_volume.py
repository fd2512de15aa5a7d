"""Closed parts' volume given back in a scan smoothed in tiles (core/mesh/tile_volume.py, cli/tiled.py): the
offsets solved from the tiles' sums are the whole mesh's, and every closed part ends with the volume it had."""

import os
import re

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from test_cli_arguments import load
from test_tiled import EXPLICIT, binary_ply, core, formats, mesh_amount, ply, smooth_tiled, tiled, torus
from test_tiled_obj import obj_text

geometry = load("core.geometry")
metrics = load("core.mesh.metrics")
tile_volume = load("core.mesh.tile_volume")
volume = load("core.mesh.volume")

AUTOMATIC = {**EXPLICIT, "alpha": core.AUTO, "beta": core.AUTO, "iterations": core.AUTO, "max_deviation": core.AUTO}
OPEN = 5  # the torus of the grid with a face taken away: open, so not restored


def tori(side, noise=0.2):
    """A side x side grid of coarse noisy tori (40 x 12 vertices each: HC takes a few per cent of their volume),
    the tori numbered along the grid, so that the tiles' boxes cut through many of them; torus OPEN open."""
    points, faces = [], []
    for k in range(side * side):
        p, f = torus(40, 12, noise=noise, seed=k)
        points.append(p + 3.2 * np.array([k % side, k // side, 0.0]))
        faces.append(f[1:] if k == OPEN else f)
        faces[-1] = faces[-1] + 480 * k
    return np.concatenate(points), np.concatenate(faces)


def in_core(data, options, sigma):
    """The whole mesh smoothed with the numbers the tiles ran, then given its volume back as the mesh pipeline
    gives it (core.mesh.volume, offsets up to NOISE_OFFSETS x the noise, then the deviation limit): (positions,
    offsets per torus), the positions smoothed only, and the file the whole route writes of the positions."""
    mesh = formats.parse(data, ".ply")
    positions = mesh.positions.astype(mesh.precision)
    edges, triangles = tiled.surface_arrays(mesh.corners, mesh.sizes)
    smoothed = core.MeshSmoother(positions, edges, faces=triangles, **options).run()
    restored, offsets = volume.restore_volume(positions, smoothed, triangles, limit=volume.NOISE_OFFSETS * sigma)
    restored = restored.astype(smoothed.dtype)
    geometry.project_rows_within(restored, positions, options["max_deviation"])
    return restored, offsets, smoothed, ply.PlyFile(formats.updated(mesh, restored))


@pytest.mark.parametrize(("keep_in_place", "capacity"), [(core.AUTO, 40_000), (False, 16_000)])
def test_closed_parts_get_their_volume_back_in_tiles(tmp_path, monkeypatch, keep_in_place, capacity):
    points, faces = tori(12)  # 144 tori, 69k vertices
    monkeypatch.setattr(mesh_amount, "WORK_BUDGET", 4 * len(points))  # 4 iterations
    data = binary_ply(points, faces, normals=True)
    run, got = smooth_tiled(tmp_path, data, {**AUTOMATIC, "keep_in_place": keep_in_place}, capacity=capacity)
    assert run.tiles >= 8 and run.restoring and run.amount.iterations == 4
    assert "143 closed parts got their volume back" in run.notes[-1]
    assert not run.change.closed and run.change.volume_change is None  # torus OPEN: the report gives no volume
    restored, offsets, smoothed, whole = in_core(data, run.options, run.amount.sigma)
    diagonal = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    result = ply.PlyFile(got).positions
    assert np.abs(result - restored).max() <= 1e-6 * diagonal
    assert abs(run.volume_offset - np.abs(offsets).max()) <= 1e-6 * diagonal
    per_torus = faces.reshape(-1) // 480
    for k in (0, OPEN, 77, 143):
        mine = faces[per_torus[::3] == k]
        before = metrics.enclosed_volume(points.astype(np.float32).astype(float), mine)
        after, lost = (metrics.enclosed_volume(p.astype(float), mine) for p in (result, smoothed))
        if k == OPEN:
            assert after == pytest.approx(metrics.enclosed_volume(smoothed.astype(float), mine), rel=1e-6)
        else:  # smoothing took more than a per cent; the offset gives it back
            assert (before - lost) / before > 0.01 and abs(after - before) <= 1e-4 * before
    # The normals the file stores are the result's, as the whole route writes them (to the positions' agreement
    # over an edge length of 0.2: Keep in Place's fold guard judges each tile on its own).
    written = ply.PlyFile(got)
    for axis in ("nx", "ny", "nz"):
        assert np.abs(written._read(written.vertex, axis) - whole._read(whole.vertex, axis)).max() <= 1e-3


def test_open_and_clean_meshes_are_left_as_smoothed(tmp_path, monkeypatch):
    monkeypatch.setattr(mesh_amount, "WORK_BUDGET", 400_000)
    points, faces = torus(400, 250)
    data = binary_ply(points, faces[1:])  # one face less: open
    run, _ = smooth_tiled(tmp_path, data, AUTOMATIC, capacity=60_000)
    assert run.restoring and run.volume_offset == 0.0
    assert "no closed part needed its volume back" in run.notes[-1]


def test_explicit_numbers_give_no_volume_back(tmp_path):
    points, faces = tori(6)
    run, _ = smooth_tiled(tmp_path, binary_ply(points, faces), EXPLICIT, capacity=12_000)
    assert not run.restoring and not any("volume" in note for note in run.notes)


def test_parts_joined_piece_by_piece():
    """Random edges, split into pieces as tiles split a mesh: the union's parts are connected_components'."""
    rng = np.random.default_rng(3)
    n = 5000
    edges = rng.integers(0, n, size=(3000, 2))
    union = tile_volume.PartUnion(n)
    for piece in np.array_split(rng.permutation(len(edges)), 7):
        graph = sp.coo_matrix((np.ones(len(piece)), tuple(edges[piece].T)), shape=(n, n))
        _, labels = connected_components(graph, directed=False)
        vertices = np.unique(edges[piece])
        union.join(vertices, np.unique(labels[vertices], return_inverse=True)[1].ravel())
    count, expected = connected_components(sp.coo_matrix((np.ones(len(edges)), tuple(edges.T)), shape=(n, n)), False)
    roots = union.find(np.arange(n))
    assert len(np.unique(roots)) == count
    pairs = np.unique(np.stack([roots, expected], axis=1), axis=0)  # the same partition: a one-to-one map
    assert len(pairs) == count
    assert np.all(roots <= np.arange(n)) and np.array_equal(roots[roots], roots)  # each part's lowest vertex


def test_an_obj_file_gets_its_volume_back_in_tiles(tmp_path, monkeypatch):
    points, faces = tori(8)
    monkeypatch.setattr(mesh_amount, "WORK_BUDGET", 4 * len(points))
    data = obj_text(points, faces, corners="v//vn", normals="vertex")
    options = {**AUTOMATIC, "keep_in_place": False}
    run, got = smooth_tiled(tmp_path, data, options, capacity=10_000, name="scan.obj")
    assert run.tiles >= 4 and "63 closed parts got their volume back" in run.notes[-1]
    assert os.listdir(tmp_path / "out") == ["scan.obj"]  # the scratch copies are gone
    mesh = formats.parse(data, ".obj")
    edges, triangles = tiled.surface_arrays(mesh.corners, mesh.sizes)
    smoothed = core.MeshSmoother(mesh.positions, edges, faces=triangles, **run.options).run()
    restored, _ = volume.restore_volume(mesh.positions, smoothed, triangles, limit=run.amount.sigma)
    geometry.project_rows_within(restored, mesh.positions, run.options["max_deviation"])
    result = formats.parse(got, ".obj").positions
    diagonal = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    assert np.abs(result - restored).max() <= 1e-6 * diagonal
    volumes = [metrics.enclosed_volume(p, faces[: 960 * 5]) for p in (mesh.positions, smoothed, result)]
    assert (volumes[0] - volumes[1]) / volumes[0] > 0.01 and abs(volumes[2] - volumes[0]) <= 1e-4 * volumes[0]


def test_parts_beyond_the_memory_limit_are_said_and_skipped(tmp_path, monkeypatch):
    points, faces = tori(6)
    monkeypatch.setattr(mesh_amount, "WORK_BUDGET", 4 * len(points))
    source, target = tmp_path / "scan.ply", tmp_path / "out" / "scan.ply"
    source.write_bytes(binary_ply(points, faces))
    n = len(points)
    # Room for a tile of the whole scan beside the lookup, not beside the parts' index too (4 bytes a vertex).
    monkeypatch.setattr(tiled, "SMALLEST_TILE", n)
    limit = tiled.BASE_BYTES + 4 * n + 24 * n + tiled.TILE_BYTES_PER_VERTEX * n + 100
    run = tiled.smooth_file(str(source), str(target), AUTOMATIC, limit)
    assert not run.restoring and "no closed part gets its volume back (raise --memory-limit)" in run.notes[1]
    # Too many pieces of parts for the share of the limit their sums may take: said, and the tiles as smoothed.
    monkeypatch.setattr(tiled, "PIECE_SHARE", 1e-9)
    options = {**AUTOMATIC, "keep_in_place": False}
    run, got = smooth_tiled(tmp_path, binary_ply(points, faces), options, capacity=12_000)
    assert run.restoring and "no closed part got its volume back (raise --memory-limit)" in run.notes[-1]
    _, _, smoothed, _ = in_core(binary_ply(points, faces), run.options, run.amount.sigma)
    assert np.array_equal(ply.PlyFile(got).positions, smoothed)


def pickled_backwards(jobs):
    """A ``runner`` as workers are to cli/tiled.py: each job pickled (as it travels to a worker), the tiles run
    last first, with a lookup of their own."""
    import pickle

    for job in reversed([pickle.loads(pickle.dumps(job)) for job in jobs]):
        yield pickle.loads(pickle.dumps(tiled.run_tile(job)))


def untimed(notes):
    return [re.sub(r"[0-9.]+ s$", "", note) for note in notes]


@pytest.mark.parametrize("name", ["scan.ply", "scan.obj"])
def test_tiles_run_anywhere_in_any_order_give_the_same_bytes(tmp_path, monkeypatch, name):
    """Tiles handed to workers (cli/batch.py's TilesOnWorkers) write only their own rows and return their sums:
    run elsewhere and in another order, the file's bytes are those of the tiles run here, one after the other."""
    points, faces = tori(8)
    monkeypatch.setattr(mesh_amount, "WORK_BUDGET", 4 * len(points))
    data = binary_ply(points, faces, normals=True) if name == "scan.ply" else obj_text(points, faces)
    for options in (AUTOMATIC, EXPLICIT):
        source, runs = tmp_path / name, []
        source.write_bytes(data)
        for folder, runner in (("here", None), ("away", pickled_backwards)):
            target = tmp_path / folder / name
            run = tiled.smooth_file(str(source), str(target), options, 8 << 30, capacity=10_000, runner=runner)
            runs.append((run, target.read_bytes()))
        (here, expected), (away, got) = runs
        assert here.tiles >= 4 and got == expected and untimed(away.notes) == untimed(here.notes)
        assert here.change.max_displacement == away.change.max_displacement
        assert here.change.rms_displacement == pytest.approx(away.change.rms_displacement, rel=1e-12)
        assert ("63 closed parts got their volume back" in here.notes[-1]) == (options is AUTOMATIC)
