"""The file route without Blender (scripts/hc_smooth_files.py, bpy unimportable) and `blender -b -c hc_smooth`
(the installed extension's command) give the same files, byte for byte, and say the same, for every kind of
scan file and the options that change what runs."""

import hashlib
import os
import pathlib
import re
import sys

import pytest
from blender_scene import ADDON

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "core"))
from file_route import OPTION_SETS, inputs_for, run_without_blender  # noqa: E402  (tests/core)


def digests(folder):
    return {path.name: hashlib.sha256(path.read_bytes()).hexdigest() for path in sorted(folder.iterdir())}


def words(text, out):
    """The command's lines without what differs between two runs: times and the output folder's name."""
    return re.sub(r"\d+\.\d\d s", "T s", text).replace(str(out), "OUT").replace(out.name, "OUT").splitlines()


@pytest.mark.parametrize("kind, options", OPTION_SETS)
def test_same_bytes_as_blender(addon, scene, tmp_path, monkeypatch, capsys, kind, options):
    monkeypatch.chdir(tmp_path)
    inputs = [os.path.relpath(path, tmp_path) for path in inputs_for(kind, tmp_path / "in", options)]
    status = sys.modules[ADDON + ".cli"].main([*inputs, "-o", "by_blender", *options])
    said = capsys.readouterr().out
    completed = run_without_blender([*inputs, "-o", "by_script", *options], cwd=tmp_path)
    assert status == 0 and completed.returncode == 0, said + completed.stdout + completed.stderr
    by_blender, by_script = digests(tmp_path / "by_blender"), digests(tmp_path / "by_script")
    assert by_blender and by_script == by_blender
    assert words(completed.stdout, tmp_path / "by_script") == words(said, tmp_path / "by_blender")
