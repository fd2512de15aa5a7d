"""--jobs and --scheduler (cli/batch.py): the file route's batches on Dask workers, run as a user runs them
(scripts/hc_smooth_files.py, bpy unimportable). The results are the serial run's bytes; a worker killed
mid-file has its file run again elsewhere; Ctrl+C stops the batch and leaves the inputs and the finished
results intact; a Python without Dask is told what to install."""

import hashlib
import os
import signal
import subprocess
import sys
import time

import dask
import distributed  # in the test environments (scripts/setup_envs.sh)
import pytest
import scan_files
from file_route import ROOT, run_without_blender, scan_folder, stl_binary, without_blender


def digests(folder):
    return {path.name: hashlib.sha256(path.read_bytes()).hexdigest() for path in sorted(folder.iterdir())}


def big_scans(folder, count, subdivisions=6):
    """``count`` noisy closed meshes of 16k vertices (binary STL), each ~a second of smoothing."""
    folder.mkdir(parents=True)
    for seed in range(count):
        positions, faces = scan_files.octahedron(noise=0.01, seed=seed, subdivisions=subdivisions)
        (folder / f"scan{seed:02d}.stl").write_bytes(stl_binary(positions, faces))
    return folder


def serial(tmp_path, scans, options=()):
    completed = run_without_blender([scans, "-o", tmp_path / "serial", *options], cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    return digests(tmp_path / "serial")


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster of 2 worker processes, as `dask scheduler` and two `dask worker` would be. A killed
    worker's nanny starts a new one; the cluster closes that nanny if no worker of its name is back within
    `lost-worker-timeout` (15 s), which a loaded machine can miss: the tests wait for the new worker."""
    with (
        dask.config.set({"distributed.deploy.lost-worker-timeout": "600s"}),
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
        distributed.Client(cluster) as client,
    ):
        yield cluster, client


def test_jobs_give_the_serial_bytes(tmp_path):
    scans = scan_folder(tmp_path / "scans")
    completed = run_without_blender([scans, "-o", tmp_path / "jobs", "--jobs", "2"], cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "4 of 4 files smoothed" in completed.stdout
    assert sorted(line[:5] for line in completed.stdout.splitlines() if line.startswith("[")) == [
        f"[{n}/4]" for n in range(1, 5)
    ]
    assert digests(tmp_path / "jobs") == serial(tmp_path, scans)
    assert not [name for name in os.listdir(tmp_path / "jobs") if name.startswith(".")]


def test_scheduler_gives_the_serial_bytes(tmp_path, cluster):
    scans = scan_folder(tmp_path / "scans")
    (scans / "broken.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nend_header\n1 2\n")
    address = cluster[0].scheduler_address
    completed = run_without_blender([scans, "-o", tmp_path / "cluster", "--scheduler", address], cwd=tmp_path)
    assert completed.returncode == 1, completed.stdout + completed.stderr
    assert "broken.ply: FAILED:" in completed.stdout and "4 of 5 files smoothed" in completed.stdout
    assert "hc_smooth: 1 of 5 files failed" in completed.stderr
    (scans / "broken.ply").unlink()
    assert digests(tmp_path / "cluster") == serial(tmp_path, scans)


def tiled_scan(folder):
    """A binary PLY of 256 coarse noisy tori (123k vertices) and the --memory-limit that smooths it in tiles
    (24 with the Automatic Amount)."""
    from test_tiled import binary_ply
    from test_tiled_volume import tori

    folder.mkdir(parents=True)
    points, faces = tori(16)
    (folder / "tori.ply").write_bytes(binary_ply(points, faces, normals=True))
    return folder, ["--memory-limit", "360M"]


def test_a_file_in_tiles_has_its_tiles_run_by_the_workers(tmp_path):
    scans, limit = tiled_scan(tmp_path / "scans")
    expected = serial(tmp_path, scans, limit)
    completed = run_without_blender([scans, "-o", tmp_path / "jobs", "--jobs", "2", *limit], cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "  its 24 tiles ran on the Dask cluster's workers" in completed.stdout.splitlines()
    assert "255 closed parts got their volume back" in completed.stdout
    assert digests(tmp_path / "jobs") == expected


def killing_a_worker(tmp_path, cluster, scans, options, pick):
    """Run the batch of ``scans`` (with ``options``) on ``cluster``'s workers and SIGKILL, once, the worker
    ``pick(client)`` names (None: not yet). Returns (the killed worker's pid, stdout, the results' digests);
    the cluster has its two workers back afterwards."""
    local, client = cluster
    pids = client.run(os.getpid)
    batch = subprocess.Popen(
        without_blender([scans, "-o", tmp_path / "cluster", "--scheduler", local.scheduler_address, *options]),
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    killed = None
    deadline = time.monotonic() + 300
    while killed is None and time.monotonic() < deadline and batch.poll() is None:
        killed = pick(client)
        if killed is not None:
            os.kill(pids[killed], signal.SIGKILL)
        time.sleep(0.05)
    out, err = batch.communicate(timeout=600)
    assert killed is not None, "the batch ended before a worker could be killed"
    assert batch.returncode == 0, out + err
    results = {name: digest for name, digest in digests(tmp_path / "cluster").items() if not name.startswith(".")}
    client.wait_for_workers(2, timeout=120)  # the nanny brings a new worker up for the next test
    return pids[killed], out, results


@pytest.mark.slow
def test_a_worker_killed_mid_tile_has_the_tile_run_again(tmp_path, cluster):
    scans, limit = tiled_scan(tmp_path / "scans")
    expected = serial(tmp_path, scans, limit)

    def tiles_running(client):  # two tasks in hand: tiles (the file's own task steps out while they run)
        processing = client.processing()
        busy = [worker for worker, keys in processing.items() if keys]
        return busy[-1] if sum(len(keys) for keys in processing.values()) >= 2 else None

    _, out, results = killing_a_worker(tmp_path, cluster, scans, limit, tiles_running)
    assert "1 of 1 files smoothed" in out and "tiles ran on the Dask cluster's workers" in out
    assert results == expected  # the lost tile (or the lost file) run again: the serial run's bytes


@pytest.mark.slow
def test_a_worker_killed_mid_file_has_the_file_run_again(tmp_path, cluster):
    scans = big_scans(tmp_path / "scans", 6)
    expected = serial(tmp_path, scans)

    def holding_a_file(client):  # a worker with a file in hand, after the first result is written
        busy = [worker for worker, keys in client.processing().items() if keys]
        written = (tmp_path / "cluster").exists() and os.listdir(tmp_path / "cluster")
        return busy[0] if busy and written else None

    pid, out, results = killing_a_worker(tmp_path, cluster, scans, (), holding_a_file)
    assert "6 of 6 files smoothed" in out
    assert results == expected  # every file whole, the lost one run again, the serial run's bytes
    leftovers = [name for name in os.listdir(tmp_path / "cluster") if name.startswith(".")]
    assert all(name.startswith(f".hc_smooth-{pid}-") for name in leftovers)  # only the lost worker's


@pytest.mark.slow
def page_faults_of_large_arrays(root, set_heap):
    """On a worker: the minor page faults of allocating and filling a 1 MiB array 100 times, after (or
    without) cli/batch.py's heap_for_large_arrays. (1 MiB: NumPy asks for transparent huge pages from 4 MiB
    on, whose faults are 2 MiB each.)"""
    import resource
    import sys

    import numpy as np

    sys.path.insert(0, root)
    import cli.standalone as standalone

    standalone.load(root)
    batch = __import__(f"{standalone.NAME}.cli.batch", fromlist=["batch"])
    if set_heap:
        assert batch.heap_for_large_arrays()
    start = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(100):
        np.ones(1 << 17)  # 1 MiB, freed at once
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - start


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc: Linux")
def test_workers_keep_large_arrays_on_their_heap():
    """Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_, which fixes glibc's mmap threshold at 128 KiB:
    every array is mapped and faulted in anew (a batch took 1.6 times as long). The task sets the thresholds
    back; then a 1 MiB array allocated again reuses the heap's pages. (A worker of its own: the module's
    cluster has run tasks.)"""
    with (
        distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as fresh,
        distributed.Client(fresh) as client,
    ):
        assert all(client.run(os.environ.get, "MALLOC_TRIM_THRESHOLD_").values())  # the nanny's setting
        plain = client.submit(page_faults_of_large_arrays, str(ROOT), False, pure=False).result()
        kept = client.submit(page_faults_of_large_arrays, str(ROOT), True, pure=False).result()
    assert plain > 100 * 128  # each array mapped anew: its 256 pages faulted in every time
    assert kept < plain / 20


def test_ctrl_c_stops_the_batch_and_keeps_what_is_finished(tmp_path):
    scans = big_scans(tmp_path / "scans", 12)
    inputs = digests(scans)
    expected = serial(tmp_path, scans)
    batch = subprocess.Popen(
        without_blender([scans, "-o", tmp_path / "jobs", "--jobs", "2"]),
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a terminal's foreground job: Ctrl+C reaches them all
    )
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and batch.poll() is None:
        if (tmp_path / "jobs").exists() and [n for n in os.listdir(tmp_path / "jobs") if not n.startswith(".")]:
            break
        time.sleep(0.05)
    assert batch.poll() is None, "the batch ended before it could be interrupted"
    os.killpg(batch.pid, signal.SIGINT)
    out, err = batch.communicate(timeout=300)
    assert batch.returncode == 130, out + err
    assert "hc_smooth: interrupted:" in err and "left as they were (no partial output written)" in err
    assert digests(scans) == inputs
    finished = digests(tmp_path / "jobs")
    assert finished and len(finished) < 12
    assert all(expected[name] == digest for name, digest in finished.items())  # no temporaries, none half-written


def test_a_python_without_dask_is_told_what_to_install(tmp_path):
    scans = scan_folder(tmp_path / "scans")
    env = {**os.environ, "TEST_BLOCKED": "dask distributed"}
    completed = run_without_blender([scans, "-o", tmp_path / "out", "--jobs", "2"], cwd=tmp_path, env=env)
    assert completed.returncode == 2, completed.stdout + completed.stderr
    assert "--jobs and --scheduler need Dask's distributed scheduler, which this Python" in completed.stderr
    assert 'python -m pip install "dask[distributed]"' in completed.stderr and "Traceback" not in completed.stderr
    assert not (tmp_path / "out").exists()
    serial_run = run_without_blender([scans, "-o", tmp_path / "out", "--jobs", "1"], cwd=tmp_path, env=env)
    assert serial_run.returncode == 0, serial_run.stderr  # one at a time needs no Dask


@pytest.mark.parametrize(
    "args, message",
    [
        (["--jobs", "0"], "0 is below 1"),
        (["--jobs", "two"], "two is not a whole number"),
        (["--jobs", "2", "--scheduler", "tcp://127.0.0.1:1"], "give either --jobs N"),
    ],
)
def test_bad_batch_options_are_refused(tmp_path, args, message):
    completed = run_without_blender(["a.ply", "-o", tmp_path / "out", *args], cwd=tmp_path)
    assert completed.returncode == 2 and message in completed.stderr, completed.stderr


def test_an_unreachable_scheduler_is_said_plainly(tmp_path):
    scans = scan_folder(tmp_path / "scans")
    completed = run_without_blender(
        [scans, "-o", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:9"], cwd=tmp_path, timeout=300
    )
    assert completed.returncode == 2, completed.stdout + completed.stderr
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in completed.stderr
    assert "Traceback" not in completed.stderr and not (tmp_path / "out").exists()
