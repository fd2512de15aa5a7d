"""One smoothing job per mesh: its arrays, the core options of the settings, the core run and the report.

Without Blender: the mesh operators read a Blender mesh into a Job and write its result back
(operators/mesh_objects.py); the command line makes one of a scan file's arrays (cli/file_route.py). Every
job is read and validated before any mesh or file is written, so a failure leaves everything as it was.

A scaled object is smoothed as it stands in the world (core.mesh.world): its positions are taken through its
stretch, so the Deviation Limit, the Automatic Amount's noise and limit, Keep Sharp Edges' angles, the report
and the deviation map measure world-space lengths in scene units; the result is mapped back to object space
on writing. An object without scale (identity, rotation, mirror) runs in object space, bit for bit as before.
A mesh shared by several objects is smoothed once, as the first of them (the active one) stands.
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import core, settings_spec

# The method's enum identifier -> the short name reports and shape keys use.
METHOD_LABEL = {choice.identifier: choice.short for choice in settings_spec.METHOD.items}
DEVIATION_ATTRIBUTE = "hc_deviation"  # the deviation map: float, on points (a mesh's attribute, a PLY's property)
DEVIATION_COLOR_ATTRIBUTE = "hc_deviation_color"  # its colours: float colour, on points


@dataclass
class Job:
    obj: object  # the Blender object and mesh it was read from; None for a file's arrays
    mesh: object
    positions: np.ndarray  # (n, 3): the mesh's or its active shape key's (float32) in ``frame``, or a file's
    edges: np.ndarray
    faces: np.ndarray  # (t, 3) triangles (a fan of each face), None for a mesh without faces
    fixed: np.ndarray  # bool (n,)
    closed: bool | None = False  # the faces enclose a volume; None: not checked yet (see input_measure)
    corners: tuple = None  # (corner_verts, corner_edges) while ``closed`` is None, if Blender gave them
    seams: bool = True  # copies of a vertex may stand on a seam: some edge has one face, or there are no faces
    influence: np.ndarray = None  # float32 (n,) weights of the influence group, if any
    key_block: object = None  # the active shape key that holds ``positions``, if any
    result: np.ndarray = None
    report: object = None  # the core.MeshReport of the run: what ran, what the Automatic Amount chose
    change: object = None  # core.Change of the result, measured once for every report
    measured_input: object = None  # Future of the core.InputMeasure the report compares with
    deviation: object = None  # the core.DeviationMap of the result (Deviation Map on), made before any write
    map_names: object = None  # where the map goes (operators: mesh_io.DeviationNames), chosen on reading
    # The object's stretch (core.mesh.world.frame): ``positions`` and ``result`` are in world-space lengths, the
    # object-space positions read are ``local``. None: object space measures as world space does.
    frame: np.ndarray = None
    local: np.ndarray = None


def core_options(props, given=frozenset()):
    """The core.MeshSmoother arguments of operator, scene or command-line settings: each setting that
    declares its ``argument`` (settings_spec). ``given``: the names the caller set (Blender's
    ``is_property_set``, the options on a command line). With the Automatic Amount on and neither Alpha
    nor Iterations given, the settings it chooses go to core as core.AUTO unless given.

    Numbers are taken in single precision, as Blender's float properties hold them, so every route runs
    the same numbers."""
    values = settings_spec.values_of(props, settings_spec.MESH)
    chosen = settings_spec.chosen(values, given)
    options = {}
    for setting in settings_spec.MESH:
        if setting.argument is None:
            continue
        value = values[setting.name]
        if setting is settings_spec.KEEP_IN_PLACE:  # on where it applies (core then decides as "auto"), else off
            value = core.AUTO if value and settings_spec.keeps_in_place(values, given) else False
        elif setting.name in chosen:
            value = core.AUTO
        elif setting.kind == "enum":
            value = next(choice.core for choice in setting.items if choice.identifier == value)
        elif setting.kind == "float":
            value = as_property(value)
        options[setting.argument] = value
    # The add-on smooths split vertices (UV seams, soups) as one, on the welded mesh, where a seam is no
    # border. Open borders: the paper's rule unless Pin Boundary holds them or Keep Outline smooths them as
    # curves (core.mesh.borders); the curve rule keeps outlines in place but measures more error to ragged scan
    # outlines (bench/README.md, "Open borders"): not the default.
    border = "fixed" if props.pin_boundary else "curve" if props.keep_outline else "free"
    options.update(weld=True, border=border)
    return options


def convergence_warning(jobs):
    """The convergence-region warning for what ran, or None. The Automatic Amount runs alpha 0 for the few
    iterations it chooses (no drift): only its beta can warn."""
    reports = [job.report for job in jobs if job.report.method == "hc" and not job.report.keep_sharp_edges]
    messages = {core.convergence_message(1.0 if r.amount else r.alpha, r.beta) for r in reports} - {None}
    return min(messages) if messages else None


def as_property(value):
    """``value`` as a Blender float property holds it (single precision)."""
    return float(np.float32(value))


def run(jobs, props, chunk=None, given=frozenset()):
    """Smooth every job with core.MeshSmoother; a generator yielding the fraction done after each chunk of
    iterations (chunk=None: each job in one slice; the result is the same bit for bit)."""
    options = core_options(props, given)
    for number, job in enumerate(jobs):
        input_measure(job)  # on the other core while this one builds the operator
        smoother = make_smoother(job, options)
        for fraction in smoother.steps(chunk):
            if fraction < 1.0:
                yield (number + fraction) / len(jobs)
        job.result, job.report = smoother.result, smoother.report
        yield (number + 1) / len(jobs)


def make_smoother(job, options):
    """The core.MeshSmoother of a job with ``core_options``' options (checks them: ValueError). A mesh
    without faces (loose edges) has no border to follow or hold; one without seams nothing to weld."""
    if job.faces is None:
        options = {**options, "border": "free"}
    if not job.seams:
        options = {**options, "weld": False}
    return core.MeshSmoother(
        job.positions,
        job.edges,
        faces=job.faces,
        fixed=job.fixed,
        influence=job.influence,
        **options,
    )


def local_result(job):
    """(the positions read, the result) of a job in object space."""
    if job.frame is None:
        return job.positions, job.result
    return job.local, core.from_frame(job.local, job.positions, job.result, job.frame)


def deviation_map(job):
    """The job's core.DeviationMap, made once: the move along the input's vertex normals (those the report
    measures along on an open mesh, made here for a closed one; world-space lengths, as the job's positions),
    in linear colours as Blender's float colour attributes hold them."""
    if job.deviation is None:
        normals = input_measure(job).result().normals
        job.deviation = core.deviation_map(job.positions, job.result, job.faces, normals=normals, linear=True)
    return job.deviation


def map_legend(job, length=None):
    """The deviation map's legend (core.DeviationMap.legend), where the map went when a name of the user's
    kept it from hc_deviation and hc_deviation_color, and where to pick its colours when the mesh's own stay
    the active ones."""
    text = deviation_map(job).legend(length)
    names = job.map_names
    if names is not None and not names.usual:
        text += f", stored in '{names.value}' and '{names.color}'"
    if names is not None and not names.shown:
        text += f"; the mesh's own colours stay active: '{names.color}' is under Color Attributes"
    return text


def input_measure(job):
    """The Future of what the report needs of the job's input (closedness, size, volume), started once
    on a background thread: the single-threaded start of a run leaves a core free for it."""
    if job.measured_input is None:
        job.measured_input = core.in_background(lambda: _measure_input(job))
    return job.measured_input


def _measure_input(job):
    closed = job.closed
    if closed is None and job.corners is not None:  # else measure_input finds it from the triangles
        closed = core.closed_from_corners(job.edges, *job.corners)
    return core.measure_input(job.positions, job.faces, closed=closed)


def measure(job):
    """What the run changed (volume of a closed mesh, else size), measured once per job."""
    if job.change is None:
        job.change = core.measure_change(job.positions, job.result, measured=input_measure(job).result())
    return job.change


def release(job):
    """Measure the job for its report, then drop its arrays: what Blender allocates next (entering Edit
    mode builds a BMesh) can reuse their memory instead of fresh pages. A deviation map keeps its legend."""
    measure(job)
    if job.deviation is not None:
        job.deviation = replace(job.deviation, deviation=None, colors=None)
    job.positions = job.result = job.local = job.edges = job.faces = job.fixed = job.influence = None
    job.corners = job.measured_input = None


def summary(jobs, props, length=None):
    """One line for the status bar: method, what ran, time, then what changed (core.Change.summary, the
    words the command line and the demo use too; with several objects, each one's after its name), and with
    Deviation Map on, each map's legend (``length`` formats its lengths, e.g. in scene units)."""
    reports = [job.report for job in jobs]
    seconds = sum(report.seconds for report in reports)
    where = " (new shape key)" if props.output == "SHAPE_KEY" else ""
    names = f"{len(jobs)} objects" if len(jobs) > 1 else f"'{jobs[0].obj.name}'"  # what the user selected
    ran = amount_words(reports)
    if len(jobs) == 1:
        changed = measure(jobs[0]).summary()
    else:
        changed = "; ".join(f"'{job.obj.name}': {measure(job).summary()}" for job in jobs)
    smoother = "Keep Sharp Edges" if any(report.keep_sharp_edges for report in reports) else METHOD_LABEL[props.method]
    text = f"{smoother} on {names}{where}: {ran}, {seconds:.2f} s; {changed}"
    if props.deviation_map:
        legends = [map_legend(job, length) for job in jobs]
        text += "; " + (
            "; ".join(f"'{j.obj.name}': {t}" for j, t in zip(jobs, legends)) if len(jobs) > 1 else legends[0]
        )
    return text


def amount_words(reports):
    """What ran: '12 iterations' or, chosen, 'automatic amount: noise 0.45x edge length, 12 iterations,
    alpha 0, beta 0.6, volume kept, moves at most 0.0123' (and '1 part left as it was (smoothing would
    change its shape)' where core.mesh.collapse gave a part back); with Keep Sharp Edges, 'sharpness 30°, ' first,
    and steps for iterations."""
    angles = sorted({round(math.degrees(r.sharpness_angle)) for r in reports if r.keep_sharp_edges})
    if not angles:
        return _amount_words(reports, "iteration")
    return f"sharpness {'/'.join(map(str, angles))}\u00b0, " + _amount_words(reports, "step")


def _amount_words(reports, unit):
    amounts = [report for report in reports if report.amount is not None]
    iterations = "/".join(str(report.iterations) for report in reports) if amounts else None
    if not amounts:
        count = max(report.iterations for report in reports)
        return f"{count} {unit}" + ("" if count == 1 else "s")
    if not any(report.amount.noise_found for report in amounts):
        if not any(report.iterations for report in reports):
            return "automatic amount: no noise found, nothing to smooth"
        most = max(report.max_deviation for report in reports)
        return f"automatic amount: light noise or none found, {iterations} {unit}s, moves at most {most:.3g}"
    noise = "/".join(f"{report.amount.ratio:.2f}" if report.amount.noise_found else "none" for report in amounts)
    words = f"automatic amount: noise {noise}x edge length, {iterations} {unit}s, alpha 0"
    words += ", beta " + "/".join(sorted({f"{report.beta:.3g}" for report in amounts}))
    if any(report.volume_offset for report in reports):
        words += ", volume kept"
    limits = [report.max_deviation for report in reports if report.max_deviation]
    if limits:
        words += f", moves at most {max(limits):.3g}"
    held = sum(report.held_parts for report in reports)
    if held:
        words += ", " + held_words(held)
    if any(report.kept_in_place for report in reports):
        words += ", kept in place"
    return words


def held_words(count):
    """'1 part left as it was (smoothing would change its shape)': the parts core.mesh.collapse gave their input
    back (the run collapsed them, or took their shape away with the noise)."""
    if count == 1:
        return "1 part left as it was (smoothing would change its shape)"
    return f"{count} parts left as they were (smoothing would change their shape)"
