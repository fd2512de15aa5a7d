"""`hc_smooth --memory-limit`: a binary PLY or OBJ whose whole run would not fit is smoothed in tiles, into the
same bytes as the whole run; what cannot go in tiles says so (cli/tiled.py; the tiling itself is tested without
Blender in tests/core/test_tiled.py)."""

import os
import sys

import numpy as np
import pytest
from blender_scene import ADDON


@pytest.fixture
def cli(addon):
    return sys.modules[ADDON + ".cli"]


def torus_ply(path, rows=400, tube=250, seed=0):
    """A noisy torus (noise 0.2 edge lengths) as binary PLY with a colour per vertex."""
    u = np.linspace(0, 2 * np.pi, rows, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, tube, endpoint=False)[None, :]
    ring = 1.0 + 0.4 * np.cos(v)
    points = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), 0.4 * np.sin(v)), -1).reshape(-1, 3)
    points += np.random.default_rng(seed).normal(0, 0.2 * 2 * np.pi * 0.4 / tube, points.shape)
    i, j = np.meshgrid(np.arange(rows), np.arange(tube), indexing="ij")
    a, b = i * tube + j, ((i + 1) % rows) * tube + j
    c, d = ((i + 1) % rows) * tube + (j + 1) % tube, i * tube + (j + 1) % tube
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    vertices = np.zeros(len(points), [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1")])
    vertices["x"], vertices["y"], vertices["z"] = points.T
    vertices["red"] = np.arange(len(points)) % 256
    records = np.zeros(len(faces), [("n", "u1"), ("i", "<i4", (3,))])
    records["n"], records["i"] = 3, faces
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\nproperty float x\nproperty float y\n"
        f"property float z\nproperty uchar red\nelement face {len(faces)}\nproperty list uchar int vertex_indices\n"
        "end_header\n"
    )
    path.write_bytes(header.encode() + vertices.tobytes() + records.tobytes())
    return path


def test_a_file_above_the_limit_goes_in_tiles_into_the_same_bytes(cli, capsys, tmp_path):
    source = torus_ply(tmp_path / "scan.ply")
    whole, tiles = tmp_path / "whole", tmp_path / "tiles"
    assert cli.main([str(source), "-o", str(whole), "--iterations", "4"]) == 0
    assert "tile" not in capsys.readouterr().out
    assert cli.main([str(source), "-o", str(tiles), "--iterations", "4", "--memory-limit", "350M"]) == 0
    out = capsys.readouterr().out
    assert "tile 1 of " in out and "smoothed in " in out and "100000 vertices, 4 iterations" in out
    assert (tiles / "scan.ply").read_bytes() == (whole / "scan.ply").read_bytes()


def test_what_cannot_go_in_tiles_says_so(cli, capsys, tmp_path):
    source = torus_ply(tmp_path / "scan.ply", rows=100, tube=60)
    argv = [str(source), "-o", str(tmp_path / "out"), "--iterations", "4", "--memory-limit", "321M"]
    assert cli.main([*argv, "--format", "obj"]) == 1
    assert "--format cannot convert it" in capsys.readouterr().out
    assert cli.main([*argv, "--deviation-attribute"]) == 1
    assert "--deviation-attribute adds a value to every vertex record" in capsys.readouterr().out
    assert cli.main([*argv, "--keep-sharp-edges"]) == 1
    assert "Keep Sharp Edges cannot run in tiles" in capsys.readouterr().out
    assert not (tmp_path / "out").exists()


def test_an_obj_above_the_limit_goes_in_tiles_into_the_same_bytes(cli, capsys, tmp_path):
    torus_ply(tmp_path / "scan.ply")
    assert (
        cli.main([str(tmp_path / "scan.ply"), "-o", str(tmp_path / "obj"), "--iterations", "0", "--format", "obj"]) == 0
    )
    source = tmp_path / "obj" / "scan.obj"
    whole, tiles = tmp_path / "whole", tmp_path / "tiles"
    assert cli.main([str(source), "-o", str(whole), "--iterations", "4"]) == 0
    capsys.readouterr()
    assert cli.main([str(source), "-o", str(tiles), "--iterations", "4", "--memory-limit", "350M"]) == 0
    out = capsys.readouterr().out
    assert "tile 1 of " in out and "smoothed in " in out and "100000 vertices, 4 iterations" in out
    assert (tiles / "scan.obj").read_bytes() == (whole / "scan.obj").read_bytes()
    assert os.listdir(tiles) == ["scan.obj"]  # no scratch file left
    assert cli.main([str(source), "-o", str(tmp_path / "out"), "--fixed-group", "g", "--memory-limit", "350M"]) == 1
    assert "--fixed-group and --influence-group read an OBJ's groups over the whole file" in capsys.readouterr().out


def test_stl_above_the_limit(cli, capsys, tmp_path, monkeypatch):
    torus_ply(tmp_path / "scan.ply", rows=100, tube=60)
    assert (
        cli.main([str(tmp_path / "scan.ply"), "-o", str(tmp_path / "stl"), "--iterations", "2", "--format", "stl"]) == 0
    )
    source = tmp_path / "stl" / "scan.stl"
    capsys.readouterr()
    argv = [str(source), "-o", str(tmp_path / "out"), "--iterations", "2"]
    assert cli.main([*argv, "--memory-limit", "1M"]) == 1  # a limit given: refused
    out = capsys.readouterr().out
    assert "above --memory-limit 1 MB, and an STL file is a triangle soup" in out and "smoothed whole" in out
    assert not (tmp_path / "out").exists()
    monkeypatch.setattr(sys.modules[ADDON + ".cli.tiled"], "default_memory_limit", lambda: 1 << 20)
    assert cli.main(argv) == 0  # the default limit: smoothed whole, with a warning
    assert "warning: its whole run may take about" in capsys.readouterr().out
