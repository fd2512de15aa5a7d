"""The benchmark suite (bench/): its runner runs every benchmark's smoke run (``--quick``) and writes a report;
the report writer keeps the latest report of each benchmark; bench/ stays apart from the tests and from core's
internals."""

import json
import pathlib
import re
import subprocess
import sys

import pytest

from bench import report, run

BENCH = run.ROOT / "bench"


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(run.BENCHMARKS))
def test_every_benchmark_runs_its_smoke_run_and_writes_a_report(name, tmp_path):
    """In the Python it names: Blender's benchmarks in this test environment (bpy), the others in .envs/bench
    (bench/README.md, "Set-up")."""
    python = pathlib.Path(sys.executable) if name in run.IN_BLENDER else run.python_for(name)
    assert python.exists(), f"{python} is missing: set up .envs/bench as bench/README.md says"
    done = subprocess.run(
        [str(python), str(BENCH / "run.py"), name, "--quick", "--output", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    (markdown,) = tmp_path.glob("*.md")
    text = markdown.read_text(encoding="utf-8")
    assert text.startswith(f"`python bench/run.py {name} --quick --output {tmp_path}`")
    assert re.search(r"^\|.*\|$", text, re.M), "the report has a table"
    assert json.loads(markdown.with_suffix(".json").read_text(encoding="utf-8"))


def test_a_report_replaces_the_earlier_one_of_its_name_and_a_failed_run_leaves_it(tmp_path):
    older = tmp_path / "bench_x-20200101-000000.md"
    older.write_text("old\n")
    older.with_suffix(".json").write_text("[]")
    other = tmp_path / "bench_x_other-20200101-000000.md"
    other.write_text("another benchmark's\n")
    with pytest.raises(RuntimeError), report.Report("bench_x", tmp_path) as out:
        out("partial")
        raise RuntimeError("the benchmark failed")
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(
        [older.name, older.name[:-3] + ".json", other.name]
    )
    with report.Report("bench_x", tmp_path) as out:
        table = out.table("mesh", "seconds", align="lr")
        table.row("torus", "1.5")
    assert not older.exists() and not older.with_suffix(".json").exists() and other.exists()
    assert out.path.read_text().splitlines() == ["| mesh | seconds |", "|---|---:|", "| torus | 1.5 |"]
    assert report.read_rows(out.path) == [{"mesh": "torus", "seconds": "1.5"}]


def test_declared_parameters_make_the_command_line(monkeypatch):
    """Types come from the defaults, sizes are read as people write them, --quick takes QUICK's values."""
    import types

    from bench.common import Parameter, repeats, sizes

    module = types.ModuleType("bench.bench_fake")
    module.PARAMETERS = (sizes("1M"), repeats(3), Parameter("alpha", 0.1), Parameter("shuffle", False))
    module.QUICK = {"sizes": "5k", "repeats": 1}
    options = run.parse("fake", module, [])
    assert (options.sizes, options.repeats, options.alpha, options.shuffle) == ([1_000_000], 3, 0.1, False)
    assert options.output == report.RESULTS
    options = run.parse("fake", module, ["--quick", "--alpha", "0.2", "--shuffle"])
    assert (options.sizes, options.repeats, options.alpha, options.shuffle) == ([5000], 1, 0.2, True)
    assert options.output == run.QUICK_OUTPUT


def test_bench_sets_sys_path_once_and_imports_neither_tests_nor_core_internals_it_patches():
    for path in BENCH.glob("*.py"):
        text = path.read_text(encoding="utf-8")
        if path.name != "run.py":
            assert "sys.path" not in text, path.name
        assert not re.search(r"^\s*(from|import) tests\b|tests/core", text, re.M), path.name
        assert not re.search(r"^\s*core\.\w+\.[A-Z_]+\s*=|setattr\((core|mesh_amount|collapse)", text, re.M), path.name
    listed = {f"{module}.py" for module in run.BENCHMARKS.values()}
    with_run = {path.name for path in BENCH.glob("bench_*.py") if "\ndef run(args, out):" in path.read_text()}
    assert with_run == listed
