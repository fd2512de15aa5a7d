"""What the benchmarks share: how a benchmark declares its parameters, the parameters every timing benchmark
has (sizes, repeats), vertex counts written as people write them, and median timing.

A benchmark is a module of bench/ listed in ``bench/run.py`` with
    PARAMETERS  a tuple of Parameter (the runner builds the command line from it)
    QUICK       parameter values of the smoke run (``--quick``: small sizes, one repeat, seconds)
    run(options, out)  the work: ``options`` the parsed parameters, ``out`` the Report (bench/report.py);
                returns its rows (``out.rows`` when it wrote its tables with ``out.table``), which the
                runner writes as JSON beside the report
and optionally ``report_name(options)`` when some options write a report of another name than the
module's. Which Python runs it: bench/run.py (IN_BLENDER).
"""

import pathlib
import statistics
import time
from typing import Callable, NamedTuple

ROOT = pathlib.Path(__file__).resolve().parents[1]  # the repository


class Parameter(NamedTuple):
    """One option of a benchmark: ``--name`` (underscores as hyphens), its default and help; ``parse``
    turns the text into the value (default: the default's type; a False default is a flag)."""

    name: str
    default: object
    help: str = ""
    parse: Callable | None = None


def count(text):
    """'1M' -> 1000000, '100k' -> 100000, '5000' -> 5000, '0' -> 0."""
    text = str(text).strip().upper()
    scale = {"K": 1_000, "M": 1_000_000}.get(text[-1:], 1)
    return int(round(float(text.rstrip("KM")) * scale))


def counts(text):
    """'100k,1M' -> [100000, 1000000]."""
    return [count(part) for part in str(text).split(",") if part.strip()]


def sizes(default, help="vertex counts, comma-separated, e.g. 100k,1M"):
    return Parameter("sizes", default, help, counts)


def repeats(default, help="runs per timing; the median is reported"):
    return Parameter("repeats", default, help, int)


def median_time(run, repeats, setup=None):
    """Median wall seconds of ``run()`` over ``repeats`` runs, ``setup()`` (untimed) before each."""
    times = []
    for _ in range(repeats):
        if setup is not None:
            setup()
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)
