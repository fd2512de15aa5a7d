"""`--jobs N` and `--scheduler ADDRESS`: a batch's scan files smoothed by worker processes, on this machine (a
Dask ``LocalCluster`` of N workers) or on a Dask distributed cluster, through one code path.

Each file is one task. A worker runs the file route (cli/file_route.py: NumPy, SciPy and dask, no Blender)
with the package loaded from the folder this one is in (cli/standalone.py), so workers on other machines
need HC Smooth at the same path, as they need the input and output folders (shared storage). Results are
written as in a serial run, whole or not at all (a temporary file in the output folder, then os.replace),
and are the serial run's bytes: the same code on the same arrays, whatever the worker or its thread count
(core/parallel.py). A worker lost mid-file: the scheduler runs the file again on another worker (up to
Dask's ``distributed.scheduler.allowed-failures`` times, then the file fails with that reason).

A file too big for memory (cli/tiled.py) runs on a worker too, and hands its tiles to the cluster's workers
(``TilesOnWorkers``): each tile is a task that reads its part of the file and writes its own vertices into the
file's temporary result, so a tile run again (its worker lost) writes the same bytes.
"""

import contextlib
import dataclasses
import logging
import os
import pathlib
import pickle
import sys

from . import files, standalone

ROOT = pathlib.Path(__file__).resolve().parents[1]  # the package's folder, which workers load the code from
NEEDS_DASK = (
    "--jobs and --scheduler need Dask's distributed scheduler, which this Python ({python}) cannot import: "
    'install it (python -m pip install "dask[distributed]"){blender}'
)
IN_BLENDER = (
    "; Blender's own Python usually has no pip packages: run the batch with "
    "`python scripts/hc_smooth_files.py --jobs N` (no Blender needed for PLY, OBJ and STL) or one Blender "
    "per file with xargs -P (docs/command_line.md)"
)


class BatchError(Exception):
    """The batch cannot start (no Dask, no scheduler, a worker that cannot run HC Smooth): nothing was written."""


def import_distributed():
    """dask.distributed, or BatchError saying how to get it."""
    try:
        import distributed
    except ModuleNotFoundError as error:
        if error.name not in ("distributed", "dask"):
            raise
        import sys

        blender = IN_BLENDER if "bpy" in sys.modules else ""
        raise BatchError(NEEDS_DASK.format(python=sys.executable, blender=blender)) from None
    return distributed


def task_of(plan):
    """What a worker needs of the plan, in plain Python values (the classes of this copy of the package may
    not import on a worker: in Blender they live under bl_ext). ``memory_limit`` is each worker's: without
    --memory-limit, --jobs N's workers share this machine's default (cli/tiled.py) N ways, and a cluster's
    workers take their own machine's."""
    from .tiled import default_memory_limit

    limit = plan.memory_limit
    if limit is None and not plan.scheduler:
        limit = default_memory_limit() // plan.jobs
    return {
        "memory_limit": limit,
        "settings": dataclasses.asdict(plan.settings),
        "given": sorted(plan.given),
        "points": plan.points,
        "point_options": dict(plan.point_options),
    }


def heap_for_large_arrays():
    """A worker's heap keeps large freed arrays for the next ones (core.memory.roomy_heap: Dask's nanny
    pins glibc's thresholds); returns whether they were set."""
    from ..core.memory import roomy_heap

    return roomy_heap()


def smooth_task(task, source, target):
    """On a worker: one file through the file route, as a serial run smooths it; returns its Outcome."""
    from . import arguments, one_file

    heap_for_large_arrays()

    plan = arguments.Plan(
        settings=arguments.Settings(**task["settings"]),
        files=[(source, target)],
        given=frozenset(task["given"]),
        points=task["points"],
        point_options=task["point_options"],
        memory_limit=task["memory_limit"],
    )
    settings = one_file.point_settings(plan) if plan.points else plan.settings
    outcome = one_file.Outcome(source=source, target=target)
    one_file.process(outcome, plan, settings, one_file.Console())
    return outcome


class TilesOnWorkers:
    """cli/tiled.py's ``runner`` on a Dask worker: the tiles of the file this worker smooths, each a task for
    any worker of its cluster (the file's task steps out of its worker's thread meanwhile: Dask's
    ``worker_client``); yields each tile's TileDone as it finishes. A tile whose worker is lost runs again
    elsewhere: it writes the same rows with the same values."""

    def __init__(self, distributed):
        self.distributed = distributed

    def __call__(self, jobs):
        with self.distributed.worker_client() as client:
            sent = (standalone.sent(standalone.on_worker_tile, str(ROOT), pickle.dumps(job)) for job in jobs)
            futures = [client.submit(pickle.loads, task, pure=False) for task in sent]  # no result shared
            try:
                for future in self.distributed.as_completed(futures):
                    yield future.result()
            finally:
                client.cancel(futures)


def tile_runner():
    """Where a tiled file's tiles run: ``TilesOnWorkers`` when this process is a Dask worker (which has imported
    distributed), else None (here)."""
    distributed = sys.modules.get("distributed")
    if distributed is None:
        return None
    try:
        distributed.get_worker()
    except ValueError:  # not in a worker's task
        return None
    return TilesOnWorkers(distributed)


def threads_per_worker(jobs):
    """The cores each of ``jobs`` local workers' smoothing threads may use (core/parallel.py)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, cores // jobs)


@contextlib.contextmanager
def connected(plan, distributed):
    """A Client of the scheduler at ``plan.scheduler``, or of a LocalCluster of ``plan.jobs`` worker
    processes (closed, its workers stopped, when the block ends, however it ends)."""
    if plan.scheduler:
        try:
            client = distributed.Client(plan.scheduler, timeout="20s")
        except Exception as error:  # noqa: BLE001 - refused, timed out, or not a Dask scheduler at all
            raise BatchError(f"cannot reach the Dask scheduler at {plan.scheduler}: {error}") from None
        with client:
            yield client
        return
    import dask  # with distributed

    # A worker killed mid-file (the memory limit, the OOM killer) is restarted by its nanny; the cluster would
    # drop it if the new one took over `lost-worker-timeout` (15 s) to start, as it can on a loaded machine.
    with dask.config.set({"distributed.deploy.lost-worker-timeout": "600s"}):
        cluster = distributed.LocalCluster(
            n_workers=plan.jobs,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",  # its HTTP server (health checks) on a free port: 8787 may be taken
            silence_logs=logging.ERROR,
            env={"HC_SMOOTH_THREADS": str(threads_per_worker(plan.jobs))},
        )
        with cluster, distributed.Client(cluster) as client:
            yield client


def check_workers(client):
    """BatchError naming every worker that cannot run HC Smooth (no such folder there, no NumPy or SciPy)."""
    problems = client.run(pickle.loads, standalone.sent(standalone.problem, str(ROOT)))
    bad = {worker: problem for worker, problem in problems.items() if problem}
    if not problems:
        raise BatchError("the Dask cluster has no workers")
    if bad:
        raise BatchError(
            "these workers cannot run HC Smooth: "
            + "; ".join(f"{worker}: {problem}" for worker, problem in sorted(bad.items()))
        )


def smooth_files(plan, pairs, done, failed):
    """Smooth the (input, output) ``pairs`` on the workers; ``done(outcome)`` is called as each file
    finishes, in the order they finish. ``failed(source, target, reason)`` makes the outcome of a file no
    worker could finish. Raises BatchError before any file runs; a KeyboardInterrupt cancels the rest and
    stops the workers (a LocalCluster's are killed) before it goes on up."""
    distributed = import_distributed()
    standalone.load(ROOT)  # the workers' results are classes of the package loaded as standalone.NAME
    task = task_of(plan)
    with connected(plan, distributed) as client:
        check_workers(client)
        futures = {
            client.submit(pickle.loads, standalone.sent(standalone.on_worker, str(ROOT), task, source, target)): (
                source,
                target,
            )
            for source, target in pairs
        }
        try:
            for future in distributed.as_completed(futures):
                try:
                    outcome = future.result()
                except Exception as error:  # noqa: BLE001 - the cluster's failure (a worker lost too often)
                    outcome = failed(*futures[future], f"{type(error).__name__}: {error}")
                done(outcome)
        finally:
            client.cancel(list(futures))
    if not plan.scheduler:  # the killed workers' temporaries: their processes are gone now
        for folder in sorted({os.path.dirname(target) for _, target in pairs}):
            files.remove_stale_temporaries(folder)
