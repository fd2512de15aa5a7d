"""The README's main job (demo/demo.py) runs headless and shows what HC is for."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PERCENT = r"([-+]\d+\.\d+) %"
ROW = re.compile(
    rf"^(Noisy|Laplacian|Laplacian, least error|HC, α [\d.]+, β [\d.]+|HC, operator defaults)"
    rf"\s+(\d+)\s+(?:{PERCENT}\s+)?{PERCENT}\s+(\d+\.\d+) %\s+{PERCENT}\s+(\d+\.\d+) %"
)
REPORT = re.compile(r"^\s+(?:Laplacian|HC) on '(.+)': .*, volume ([-+]\d+\.\d+)%$")


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """One run with a tiny picture: the whole path, render included, in seconds."""
    out = tmp_path_factory.mktemp("demo")
    run = subprocess.run(
        [
            sys.executable,
            str(ROOT / "demo" / "demo.py"),
            "--iterations",
            "10",
            "--samples",
            "1",
            "--scale",
            "10",
            "--output-dir",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    rows = {}
    for line in run.stdout.splitlines():
        match = ROW.match(line)
        if match:
            name = "HC fixed" if match[1].startswith("HC, α") else match[1]
            rows[name] = {
                "iterations": int(match[2]),
                "change": None if match[3] is None else float(match[3]),
                "vs_clean": float(match[4]),
                "rms": float(match[5]),
                "mean": float(match[6]),
            }
    reports = {match[1]: float(match[2]) for match in map(REPORT.match, run.stdout.splitlines()) if match}
    return run, out, rows, reports


def test_demo_prints_a_table_where_hc_keeps_the_volume_laplacian_loses(demo):
    run, out, rows, _ = demo
    expected = {"Noisy", "Laplacian", "Laplacian, least error", "HC fixed", "HC, operator defaults"}
    assert set(rows) == expected, run.stdout
    assert rows["Laplacian"]["iterations"] == rows["HC fixed"]["iterations"] == 10  # equal counts
    for hc in ("HC fixed", "HC, operator defaults"):
        assert abs(rows[hc]["change"]) < 0.5 and abs(rows[hc]["mean"]) < 0.02  # volume, mean signed distance
        assert rows[hc]["rms"] < rows["Noisy"]["rms"] and rows[hc]["rms"] < rows["Laplacian"]["rms"]
    assert rows["Laplacian"]["change"] < -2.0 and rows["Laplacian"]["mean"] < -0.05  # shrunk: inside the clean shape
    # Its best count is the best: no more error than the fixed count, still smaller than the input.
    assert rows["Laplacian, least error"]["rms"] <= rows["Laplacian"]["rms"]
    assert rows["Laplacian, least error"]["change"] < 0.0
    assert (out / "hc_smooth_demo.blend").exists()


def test_the_table_and_the_operator_report_the_same_volume_change(demo):
    run, _, rows, reports = demo
    names = {
        "Laplacian": "Laplacian",
        "Laplacian, least error": "Laplacian, least error",
        "HC, operator defaults": "HC, operator defaults",
    }
    names.update({name: "HC fixed" for name in reports if name.startswith("HC, α")})
    assert set(reports) == set(names), run.stdout  # a volume for every run: the mesh is closed
    for report_name, row in names.items():
        assert reports[report_name] == rows[row]["change"], (report_name, run.stdout)
    assert "size" not in "".join(line for line in run.stdout.splitlines() if " on '" in line)


def test_the_demo_renders_without_cycles_progress_lines(demo):
    run, out, _, _ = demo
    assert (out / "comparison.png").stat().st_size > 1000
    printed = run.stdout + run.stderr
    assert "Fra:" not in printed and "Sample " not in printed, printed[-2000:]
    assert re.search(r"^picture: .*comparison\.png", run.stdout, re.M)


def test_captured_collects_what_c_code_and_python_print(capfd):
    import console_capture  # the repository root is on sys.path (conftest), as for the demo

    with console_capture.captured() as lines:
        os.write(1, b"Fra:1 Mem:8.20M | Synchronizing object\n")
        os.write(2, b"from C on stderr\n")
        print("from Python")
    print("after")
    assert lines == ["Fra:1 Mem:8.20M | Synchronizing object", "from C on stderr", "from Python"]
    assert capfd.readouterr().out == "after\n"
