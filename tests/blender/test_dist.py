"""The distribution: `scripts/dist.py` builds per-platform zips with SciPy wheels; the zip of this
platform, installed into an empty Blender user folder, brings its own SciPy (not the test environment's)
and the operator and the command work from it. Runs on whichever bpy this suite runs on (4.5: cp311
wheel, 5.2: cp313 wheel). Only this platform's zip is built: the first run downloads its two SciPy
wheels (cp311 and cp313, ~35 MB each) into build/wheels, later runs reuse them."""

import json
import os
import pathlib
import platform
import subprocess
import sys
import tomllib
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import dist  # noqa: E402


def host_platform():
    """This machine as Blender names platforms (dist.PLATFORMS)."""
    machine = {"amd64": "x64", "x86_64": "x64", "arm64": "arm64", "aarch64": "arm64"}[platform.machine().lower()]
    system = {"linux": "linux", "darwin": "macos", "win32": "windows"}[sys.platform]
    return f"{system}-{machine}"


HOST = host_platform()


@pytest.fixture(scope="session")
def dist_zip(tmp_path_factory):
    work = tmp_path_factory.mktemp("dist")
    (work / "tmp").mkdir()
    completed = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "dist.py"),
            "--output-dir",
            str(work / "dist"),
            "--cache",
            str(ROOT / "build" / "wheels"),
            "--platform",
            HOST,
        ],
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ, "TMPDIR": str(work / "tmp")},
    )
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert not list((work / "tmp").iterdir()), "dist.py left its staging folder"
    zips = sorted((work / "dist").glob("hc_smooth-*.zip"))
    yield zips
    for path in zips:  # ~70 MB each
        path.unlink()


def test_zip_for_this_platform_with_both_pythons_and_no_numpy(dist_zip):
    (path,) = dist_zip
    assert path.stem.endswith(HOST.replace("-", "_"))
    names = zipfile.ZipFile(path).namelist()
    wheels = sorted(name for name in names if name.endswith(".whl"))
    assert [name.split("-")[:3] for name in wheels] == [
        ["wheels/scipy", "1.15.3", "cp311"],
        ["wheels/scipy", wheels[1].split("-")[1], "cp313"],
    ]
    assert wheels[1].split("-")[1].startswith("1.17.")
    tag = {"windows-x64": "win_amd64", "macos-x64": "_x86_64", "macos-arm64": "_arm64", "linux-x64": "linux"}[HOST]
    assert all(tag in name for name in wheels), wheels
    assert not any("numpy" in name.lower() for name in names)
    assert not any(
        name.split("/")[0] in {"tests", "bench", "docs", "examples", "scripts", ".ci", "demo"} for name in names
    )
    assert "cli/command.py" in names and "core/__init__.py" in names
    manifest = tomllib.loads(zipfile.ZipFile(path).read("blender_manifest.toml").decode())
    assert manifest["platforms"] == [HOST] and len(manifest["wheels"]) == 2


def fake_pip_download(requested):
    """Stands in for `pip download`: records the platform tags asked for and writes an empty wheel."""

    def run(command, check):
        tags = [command[i + 1] for i, arg in enumerate(command) if arg == "--platform"]
        requested.append(tags)
        dest = pathlib.Path(command[command.index("--dest") + 1])
        (dest / f"scipy-1.0-{command[command.index('--python-version') + 1]}-{tags[0]}.whl").touch()

    return run


def test_one_platform_downloads_its_two_wheels_only(tmp_path, monkeypatch):
    requested = []
    monkeypatch.setattr(dist.subprocess, "run", fake_pip_download(requested))
    wheels = dist.download_wheels(tmp_path, (HOST,))
    assert requested == [list(dist.PLATFORMS[HOST])] * 2 and len(wheels) == 2
    assert sorted(folder.name for folder in tmp_path.iterdir()) == [f"cp311-{HOST}", f"cp313-{HOST}"]


def test_make_dist_still_builds_every_platform(tmp_path, monkeypatch):
    requested = []
    monkeypatch.setattr(dist.subprocess, "run", fake_pip_download(requested))
    wheels = dist.download_wheels(tmp_path)  # the default of `make dist`
    assert len(wheels) == 2 * len(dist.PLATFORMS) and len(requested) == 2 * len(dist.PLATFORMS)
    manifest = dist.manifest_with_wheels((ROOT / "blender_manifest.toml").read_text(), [w.name for w in wheels])
    assert tomllib.loads(manifest)["platforms"] == list(dist.PLATFORMS)


def test_zip_for_this_platform_installs_and_uses_its_own_scipy(dist_zip, tmp_path):
    completed = subprocess.run(
        [sys.executable, str(pathlib.Path(__file__).with_name("dist_driver.py")), str(dist_zip[0]), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    lines = [line for line in completed.stdout.splitlines() if line.startswith("REPORT ")]
    assert lines, completed.stdout + completed.stderr
    report = json.loads(lines[-1][len("REPORT ") :])
    assert "error" not in report, report
    assert report["install"] == ["FINISHED"] and report["enabled"]
    site = report["site_packages"]
    # The environment has a SciPy, hidden as Blender's Python has none: nothing to import before the install ...
    assert report["env_scipy_exists"] and report["scipy_before_install"] is None
    # ... and after it, the wheel for this Python, unpacked by Blender into the extensions' site-packages.
    assert report["scipy_file"].startswith(site), report
    assert report["scipy_sparse_file"].startswith(site), report
    python = f"cp{sys.version_info[0]}{sys.version_info[1]}"
    expected = "1.15.3" if python == "cp311" else "1.17."
    assert report["scipy_version"].startswith(expected)
    assert [name for name in report["dist_infos"] if name.startswith("scipy")] == [
        f"scipy-{report['scipy_version']}.dist-info"
    ]
    assert "numpy" not in " ".join(report["dist_infos"]).lower()
    assert "/extensions/user_default/hc_smooth/core/" in report["extension_core_file"]
    assert report["operator"] == ["FINISHED"] and report["operator_moved"] > 100
    assert report["command_status"] == 0 and report["command_outputs"] == ["scan.stl"]
