"""A benchmark's report: every line to stdout and to ``<results>/<name>-<time>.md``, the rows behind it to a
JSON file of the same name (git tracks the markdown and ignores the JSON and NPZ files beside it).

A report replaces the earlier reports of the same name once it is complete (git keeps them); a run that
fails leaves the earlier ones and removes its own partial file.
"""

import json
import pathlib
import time

RESULTS = pathlib.Path(__file__).resolve().parent / "results"


class Report:
    """``with Report("bench_x") as out: out(line)``; ``out.table(...)`` writes a markdown table row by row
    and keeps its rows; ``out.path`` is the markdown file, ``out.sibling(".npz")`` the same name with another
    suffix. Says where it wrote on leaving."""

    def __init__(self, name, directory=RESULTS):
        self.name = name
        self.directory = pathlib.Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.path = self.directory / f"{name}-{time.strftime('%Y%m%d-%H%M%S')}.md"
        self.rows = []
        self.data = None  # what the benchmark returned: written as JSON beside the report
        self._handle = None

    def __enter__(self):
        self._handle = self.path.open("w", encoding="utf-8")
        return self

    def __call__(self, line=""):
        print(line, flush=True)
        self._handle.write(line + "\n")

    def table(self, *columns, align=""):
        """A markdown table with these column titles; ``align`` one letter per column, ``r`` right-aligned
        (numbers), anything else left. Returns the table: ``table.row(*cells)`` writes a row."""
        return Table(self, columns, align)

    def sibling(self, suffix):
        return self.path.with_suffix(suffix)

    def __exit__(self, kind, *_):
        self._handle.close()
        if kind is not None:
            self.path.unlink(missing_ok=True)
            return
        data = self.rows if self.data is None else self.data
        self.sibling(".json").write_text(json.dumps(data, indent=1, default=_plain), encoding="utf-8")
        for older in self.directory.glob(f"{self.name}-*"):
            if older.stem != self.path.stem and older.stem[len(self.name) + 1 :].replace("-", "").isdigit():
                older.unlink()
        print(f"\n(written to {self.path})")


class Table:
    def __init__(self, report, columns, align):
        self.report, self.columns = report, columns
        report("| " + " | ".join(columns) + " |")
        report("|" + "".join("---:|" if align[k : k + 1] == "r" else "---|" for k in range(len(columns))))

    def row(self, *cells):
        if len(cells) != len(self.columns):
            raise ValueError(f"{len(cells)} cells for {len(self.columns)} columns")
        self.report("| " + " | ".join(str(cell) for cell in cells) + " |")
        self.report.rows.append(dict(zip(self.columns, cells)))


def read_rows(path):
    """What the JSON file beside the report at ``path`` holds (the rows its benchmark returned)."""
    return json.loads(pathlib.Path(path).with_suffix(".json").read_text(encoding="utf-8"))


def _plain(value):
    """NumPy scalars and arrays as JSON numbers and lists."""
    return value.tolist() if hasattr(value, "tolist") else str(value)
