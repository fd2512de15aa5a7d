"""The README's main job (demo/demo.py) runs headless and shows what HC is for."""

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_demo_prints_a_table_where_hc_keeps_the_volume_laplacian_loses(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "demo" / "demo.py"), "--no-render", "--iterations", "10",
                          "--output-dir", str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    rows = {}
    for line in run.stdout.splitlines():
        match = re.match(r"^(Noisy|Laplacian|HC|HC sequential)\s+\d+\s+[\d.]+\s+([-+][\d.]+) %\s+([\d.]+) %", line)
        if match:
            rows[match[1]] = (float(match[2]), float(match[3]))
    assert set(rows) == {"Noisy", "Laplacian", "HC", "HC sequential"}, run.stdout
    assert abs(rows["HC"][0]) < 0.5 and rows["Laplacian"][0] < -2.0  # volume change, %
    assert rows["HC"][1] < rows["Noisy"][1] and rows["HC"][1] < rows["Laplacian"][1]  # error to the clean shape
    assert (tmp_path / "hc_smooth_demo.blend").exists()
