"""Keep in Place (core.mesh.in_place): where to remove the slide, and what Keep Sharp Edges slides.

Cells: a mesh of bench_quality_inputs with noise (``--cells mesh/kind/sigma,...``; the noise as
bench_default_heldout.py makes it, the real scans' truth as stored). For each, three measures in % of the
bounding-box diagonal (bench/README.md): RMS distance to the clean surface, RMS distance of each vertex to
its own clean position, and the slide (RMS along-surface part of each vertex's move against the clean
vertex normal), of

* HC's default, Keep in Place after the iterations (``core.smooth_mesh(..., weld=True)``);
* HC's default sliding (``keep_in_place=False``);
* the same iterations (alpha 0, the default's beta) with each iteration's move projected onto the current
  vertex normals: the slide removed inside the iteration instead of after it;
* Keep Sharp Edges (``keep_sharp_edges=True``) and Keep Sharp Edges with ``keep_in_place=True``.

    .envs/bench/bin/python bench/bench_keep_in_place.py            # the cells of docs/keep_in_place.md (~3 min)
"""

import warnings

import numpy as np

import core
from bench import bench_default_heldout as heldout
from bench import bench_quality_inputs as inputs
from bench.common import Parameter
from core.geometry import vertex_normals

CELLS = "face/normal/0.005,cow/normal/0.0025,bunny10k/normal/0.0025,cube/normal/0.0025,cube/iso/0.0025"


def measures(case, result, clean_normals):
    move = result - case.noisy
    slide = move - np.einsum("ij,ij->i", move, clean_normals)[:, None] * clean_normals
    return (
        case.rms(result),
        float(np.sqrt(np.mean(np.sum((result - case.clean) ** 2, axis=1))) / case.diagonal),
        float(np.sqrt(np.mean(np.sum(slide**2, axis=1))) / case.diagonal),
    )


def every_iteration(case, beta, iterations):
    """HC (alpha 0) one iteration at a time, each iteration's move kept to the current normals. With alpha 0
    an iteration reads only the current positions, so chained single iterations are one run."""
    current = case.noisy
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        for _ in range(iterations):
            step = core.hc_smooth(current, case.edges, alpha=0.0, beta=beta, iterations=1)
            normals = vertex_normals(step, case.faces)
            along = np.einsum("ij,ij->i", step - current, normals)
            current = current + along[:, None] * normals
    return current


def runs(case):
    kept, report = core.smooth_mesh(case.noisy, case.edges, faces=case.faces, weld=True, return_report=True)
    yield "HC default, Keep in Place", kept
    yield (
        "HC default, sliding",
        core.smooth_mesh(case.noisy, case.edges, faces=case.faces, weld=True, keep_in_place=False),
    )
    yield f"every iteration projected ({report.iterations} it.)", every_iteration(case, report.beta, report.iterations)
    sharp = dict(faces=case.faces, weld=True, keep_sharp_edges=True)
    yield "Keep Sharp Edges", core.smooth_mesh(case.noisy, case.edges, **sharp)
    yield "Keep Sharp Edges, keep_in_place=True", core.smooth_mesh(case.noisy, case.edges, keep_in_place=True, **sharp)


PARAMETERS = (Parameter("cells", CELLS, "mesh/kind/sigma, comma-separated"),)
QUICK = {"cells": "cube/iso/0.0025"}


def run(args, out):
    table = out.table("cell", "run", "surface", "vertex", "slide", align="llrrr")
    for cell in inputs.parse_list(args.cells):
        mesh, kind, sigma = cell.split("/")
        case = heldout.make_case(mesh, kind, float(sigma), 0)
        clean_normals = inputs.vertex_normals(case.clean, case.faces)
        for label, result in runs(case):
            surface, vertex, slide = measures(case, result, clean_normals)
            table.row(cell, label, f"{100 * surface:.4f}", f"{100 * vertex:.4f}", f"{100 * slide:.4f}")
    return out.rows
