"""The file route: a PLY, OBJ or STL file smoothed without Blender, in any Python with NumPy and SciPy.

cli/formats reads the file; its arrays go to the smoothing jobs (jobs/: the mesh operators' job code, the
point operator's with --points), in the precision the file stores; cli/files writes the result whole or
not at all. ``smooth_jobs`` and ``smooth_clouds`` count what the jobs did into the file's Outcome; the
.blend route (cli/blend.py) runs its objects' jobs through them too.
"""

import os
import time
import warnings

import numpy as np

from .. import core
from ..jobs import mesh as mesh_jobs
from ..jobs import points
from . import batch, files, tiled
from .files import FileError


def smooth_mesh_file(outcome, plan, settings, console):
    limit = plan.memory_limit or tiled.default_memory_limit()
    if tiled.needs_tiles(outcome.source, limit) and tiles_apply(outcome, plan, limit):
        try:
            smooth_tiled_file(outcome, plan, settings, console, limit)
            return
        except tiled.FormatError as error:  # found by the index pass, before anything is written
            not_tiled(outcome, plan, limit, f"it cannot be smoothed in tiles: {error}")
    console.stage(outcome, "reading", outcome.source)
    mesh = files.read_mesh(outcome.source)
    console.stage(outcome, "smoothing", outcome.source)
    outcome.progress = console.progress(outcome, time.perf_counter())
    name = os.path.splitext(os.path.basename(outcome.source))[0]
    wanted = {plan.settings.vertex_group, plan.settings.influence_group} - {""}
    groups = mesh.groups(wanted) if wanted and hasattr(mesh, "groups") else {}
    positions = mesh.positions.astype(mesh.precision, copy=False)  # no copy when the file holds doubles
    result, added = smooth_arrays(name, positions, mesh.corners, mesh.sizes, plan, settings, outcome, groups)
    console.stage(outcome, "writing", outcome.target)
    files.write_bytes(outcome.target, files.result_bytes(mesh, result, outcome.target, added))


def tiles_apply(outcome, plan, limit):
    """Whether a file too big for ``limit`` goes in tiles: a binary PLY or OBJ mesh does (an OBJ's layout is
    checked by the tiled run's first pass); anything else runs whole, with a warning, or fails when the limit
    was given (--memory-limit)."""
    ext = os.path.splitext(outcome.source)[1].lower()
    if plan.points:
        return not_tiled(outcome, plan, limit, "point clouds are smoothed whole")
    if ext == ".stl":
        return not_tiled(outcome, plan, limit, tiled.STL_REFUSAL)
    if ext == ".ply":
        try:
            tiled.PlyBlocks(outcome.source)
        except (tiled.FormatError, OSError) as error:
            return not_tiled(outcome, plan, limit, f"it cannot be smoothed in tiles: {error}")
    return True


def not_tiled(outcome, plan, limit, problem):
    """A file too big for ``limit`` that cannot run tiled for ``problem``: it fails when the limit was given,
    else it runs whole with a warning (returns False)."""
    needed = tiled.size_words(tiled.in_core_bytes(tiled.estimated_vertices(outcome.source)))
    if plan.memory_limit:
        raise FileError(
            f"its whole run would take about {needed}, above --memory-limit {tiled.size_words(limit)}, and {problem}"
        )
    outcome.warnings.append(f"its whole run may take about {needed}, above {tiled.size_words(limit)}; {problem}")
    return False


def smooth_tiled_file(outcome, plan, settings, console, limit):
    """A binary PLY or OBJ file larger than the memory limit, smoothed in tiles straight into its target
    (cli/tiled.py)."""
    console.stage(outcome, "smoothing", outcome.source)
    name = os.path.splitext(os.path.basename(outcome.source))[0]
    ext = os.path.splitext(outcome.source)[1].lower()
    if os.path.splitext(outcome.target)[1].lower() != ext:
        raise FileError(
            f"a scan smoothed in tiles is written as it is read ({ext[1:].upper()}): --format cannot convert it"
        )
    if plan.settings.deviation_map:
        raise FileError(
            "--deviation-attribute adds a value to every vertex record, which a scan smoothed in tiles cannot"
        )
    for group in (plan.settings.vertex_group, plan.settings.influence_group):
        if group and ext == ".obj":
            raise FileError(
                "--fixed-group and --influence-group read an OBJ's groups over the whole file: they cannot run in "
                "tiles (raise --memory-limit to smooth it whole)"
            )
        group_mask(name, {}, group, False, 0)  # a PLY file has no vertex groups: the whole route's message
    options = mesh_jobs.core_options(settings, plan.given)
    runner = batch.tile_runner()  # on a batch's worker: the tiles go to the cluster's workers
    run = tiled.smooth_file(
        outcome.source, outcome.target, options, limit, say=lambda text: console.say(f"  {text}"), runner=runner
    )
    if runner is not None:
        run.notes.append(f"its {run.tiles} tiles ran on the Dask cluster's workers")
    outcome.objects, outcome.vertices, outcome.iterations = 1, run.vertices, run.iterations
    outcome.kept = run.kept_in_place
    outcome.changes.append(run.change)
    outcome.notes.extend(run.notes)


def smooth_arrays(name, positions, corners, sizes, plan, settings, outcome, groups=None):
    """(smoothed positions, {name: vertex values}) of a file's mesh: vertex ``positions`` (in the precision
    the smoothing runs in) and faces given as ``corners`` (vertex indices, face after face) with ``sizes``
    (corners per face; faces of fewer than three corners, or with a corner repeating the one before it,
    take no part). No faces: a point cloud (--points). ``groups``: {name: vertex indices} for
    --fixed-group and --influence-group (an OBJ's groups, weight 1). ``name`` is what messages call the
    mesh. The values are what the file takes besides the positions: the deviation map with
    --deviation-attribute, else none.

    The one place that hands a file's arrays to the smoothing, through the operators' job code (jobs/: the
    same options and checks, the same core run) but not through a Blender mesh, which would hold them in
    single precision."""
    n = len(positions)
    fixed = group_mask(name, groups, plan.settings.vertex_group, plan.settings.invert_vertex_group, n)
    if plan.points:
        if np.any(sizes >= 3):
            raise FileError(f"'{name}' has edges: it is a mesh, not a point cloud (smooth it without --points)")
        check_point_groups(plan.settings)
        points.check_settings(settings)  # as the operator checks its settings
        cloud = points.Cloud(name, positions, fixed)
        smooth_clouds([cloud], settings, outcome)
        outcome.objects = 1
        return cloud.result, {}
    influence = group_mask(name, groups, plan.settings.influence_group, plan.settings.invert_influence_group, n)
    job = mesh_job(name, positions, corners, sizes, fixed, None if influence is None else influence.astype(float))
    smooth_jobs([job], settings, outcome, plan.given)
    outcome.objects = 1
    added = {}
    if plan.settings.deviation_map:
        added[mesh_jobs.DEVIATION_ATTRIBUTE] = mesh_jobs.deviation_map(job).deviation.astype(np.float32)
    return job.result, added


def check_point_groups(settings):
    if settings.influence_group:
        raise FileError("--influence-group is for meshes: point clouds take --fixed-group only")


def group_mask(name, groups, group, invert, n):
    """The ``n`` vertices' membership of vertex group ``group`` (bool, inverted if asked), None without one."""
    if not group:
        return None
    members = (groups or {}).get(group)
    if members is None:
        raise FileError(f"Object '{name}' has no vertex group '{group}'")
    mask = np.zeros(n, dtype=bool)
    mask[members] = True
    return ~mask if invert else mask


def mesh_job(name, positions, corners, sizes, fixed, influence):
    """A job of the mesh operators (jobs.mesh.Job) for a file's arrays: its edges are the sides of
    the faces Blender would keep (at least three corners, none repeating the one before it)."""
    n = len(positions)
    if n == 0:
        raise FileError(f"Mesh '{name}' has no vertices: nothing to smooth")
    edges, faces = tiled.surface_arrays(corners, sizes)
    if not len(edges):
        raise FileError(f"'{name}' has no edges: it is a point cloud (pass --points to smooth it as one)")
    fixed = np.zeros(n, dtype=bool) if fixed is None else fixed
    return mesh_jobs.Job(None, None, positions, edges, faces, fixed, closed=None, influence=influence)


def smooth_jobs(jobs, settings, outcome, given):
    """Run the mesh operators' jobs and count what they did into ``outcome``; writes nothing."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)  # said once, at the start
        # chunk=1: a slice an iteration, the same result as in one go; the slices give the progress lines
        for fraction in mesh_jobs.run(jobs, settings, chunk=1 if outcome.progress else None, given=given):
            if outcome.progress:
                outcome.progress(fraction)
    for job in jobs:
        outcome.changes.append(mesh_jobs.measure(job))
        if settings.deviation_map:
            legend = mesh_jobs.map_legend(job)
            outcome.legends.append(f"'{job.obj.name}': {legend}" if len(jobs) > 1 else legend)
        outcome.vertices += len(job.positions)
        outcome.iterations = max(outcome.iterations, job.report.iterations)
        outcome.sharp = outcome.sharp or job.report.keep_sharp_edges
        outcome.held += job.report.held_parts
        outcome.kept = outcome.kept or job.report.kept_in_place


def smooth_clouds(clouds, settings, outcome):
    """Run the point operator's clouds and count what they did into ``outcome``; writes nothing."""
    for _ in points.run(clouds, settings):
        pass
    for cloud in clouds:
        outcome.changes.append(core.measure_change(cloud.positions, cloud.result))
        outcome.vertices += len(cloud.positions)
        outcome.rounds.append((cloud.report.rounds, cloud.report.iterations_per_round))
    outcome.warnings.extend(text for text in (points.stuck_warning(clouds),) if text)
