"""The distribution: `scripts/dist.py` builds per-platform zips with SciPy wheels; the linux-x64 zip,
installed into an empty Blender user folder, brings its own SciPy (not the test environment's) and
the operator and the command work from it. Runs on whichever bpy this suite runs on (4.5: cp311
wheel, 5.2: cp313 wheel). Needs PyPI the first time; wheels are cached in build/wheels."""

import json
import pathlib
import subprocess
import sys
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
PLATFORMS = ("windows_x64", "macos_x64", "macos_arm64", "linux_x64")


@pytest.fixture(scope="session")
def dist_zips(tmp_path_factory):
    work = tmp_path_factory.mktemp("dist")
    completed = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "dist.py"), "--output-dir", str(work / "dist"),
         "--staging", str(work / "staging"), "--cache", str(ROOT / "build" / "wheels")],
        capture_output=True, text=True, timeout=900)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    zips = {path.stem.split("-")[-1]: path for path in (work / "dist").glob("hc_smooth-*.zip")}
    yield zips
    for path in zips.values():  # ~70 MB each
        path.unlink()


def test_one_zip_per_platform_with_both_pythons_and_no_numpy(dist_zips):
    assert sorted(dist_zips) == sorted(PLATFORMS)
    for platform, path in dist_zips.items():
        names = zipfile.ZipFile(path).namelist()
        wheels = sorted(name for name in names if name.endswith(".whl"))
        assert [name.split("-")[:3] for name in wheels] == [
            ["wheels/scipy", "1.15.3", "cp311"], ["wheels/scipy", wheels[1].split("-")[1], "cp313"]]
        assert wheels[1].split("-")[1].startswith("1.17.")
        tag = {"windows_x64": "win_amd64", "macos_x64": "_x86_64", "macos_arm64": "_arm64",
               "linux_x64": "linux"}[platform]
        assert all(tag in name for name in wheels), wheels
        assert not any("numpy" in name.lower() for name in names)
        assert not any(name.split("/")[0] in {"tests", "bench", "docs", "examples", "scripts", ".ci", "demo"}
                       for name in names)
        assert "cli/command.py" in names and "core/__init__.py" in names
        manifest = zipfile.ZipFile(path).read("blender_manifest.toml").decode()
        assert "wheels = [" in manifest


def test_linux_zip_installs_and_uses_its_own_scipy(dist_zips, tmp_path):
    completed = subprocess.run([sys.executable, str(pathlib.Path(__file__).with_name("dist_driver.py")),
                                str(dist_zips["linux_x64"]), str(tmp_path)],
                               capture_output=True, text=True, timeout=300)
    lines = [line for line in completed.stdout.splitlines() if line.startswith("REPORT ")]
    assert lines, completed.stdout + completed.stderr
    report = json.loads(lines[-1][len("REPORT "):])
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
        f"scipy-{report['scipy_version']}.dist-info"]
    assert "numpy" not in " ".join(report["dist_infos"]).lower()
    assert "/extensions/user_default/hc_smooth/core/" in report["extension_core_file"]
    assert report["operator"] == ["FINISHED"] and report["operator_moved"] > 100
    assert report["command_status"] == 0 and report["command_outputs"] == ["scan.stl"]
