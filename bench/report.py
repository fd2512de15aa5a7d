"""A benchmark's report: every line to stdout and to bench/results/<name>-<time>.md (tracked by git, which
ignores the JSON and NPZ files beside it)."""

import pathlib
import time

RESULTS = pathlib.Path(__file__).resolve().parent / "results"


class Report:
    """``with Report("bench_x") as out: out(line)``; ``out.path`` is the markdown file, ``out.sibling(".json")``
    the same name with another suffix (for the numbers behind it). Says where it wrote on leaving."""

    def __init__(self, name):
        RESULTS.mkdir(exist_ok=True)
        self.path = RESULTS / f"{name}-{time.strftime('%Y%m%d-%H%M%S')}.md"
        self._handle = None

    def __enter__(self):
        self._handle = self.path.open("w")
        return self

    def __call__(self, line=""):
        print(line, flush=True)
        self._handle.write(line + "\n")

    def sibling(self, suffix):
        return self.path.with_suffix(suffix)

    def __exit__(self, *_):
        self._handle.close()
        print(f"\n(written to {self.path})")
