"""Blender's own smoothing modifiers on the quality benchmark's noisy meshes (run by bench_quality.py
--blender in .envs/bpy45; not meant to be run by hand).

    .envs/bpy45/bin/python -m bench.bench_quality_blender JOBS.npz RESULTS.npz   # in the repository's folder

JOBS.npz holds, per job i: ``vertices_i`` (n, 3), ``faces_i`` (f, 3), ``modifier_i`` ("SMOOTH" or
"LAPLACIANSMOOTH"), ``settings_i`` (a JSON object of modifier properties; empty: Blender's defaults)
and ``repeats_i``. RESULTS.npz gets ``positions_i`` (the evaluated vertex positions) and ``seconds_i``
(the median time of evaluating the modifier, depsgraph update included).
"""

import json
import statistics
import sys
import time

from scripts.extension_session import run_and_exit  # before bpy: a throw-away Blender user folder

# isort: split

import bpy
import numpy as np


def mesh_object(vertices, faces):
    mesh = bpy.data.meshes.new("noisy")
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(vertices, np.float32).ravel())
    mesh.loops.add(faces.size)
    mesh.loops.foreach_set("vertex_index", np.ascontiguousarray(faces, np.int32).ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new("noisy", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def evaluate(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    evaluated = obj.evaluated_get(depsgraph)
    positions = np.empty(len(evaluated.data.vertices) * 3)
    evaluated.data.vertices.foreach_get("co", positions)
    return positions.reshape(-1, 3)


def main():
    jobs_path, results_path = sys.argv[-2:]
    jobs = np.load(jobs_path, allow_pickle=False)
    count = int(jobs["count"])
    results = {}
    for i in range(count):
        bpy.ops.wm.read_homefile(use_empty=True)
        obj = mesh_object(jobs[f"vertices_{i}"], jobs[f"faces_{i}"])
        modifier = obj.modifiers.new("smooth", str(jobs[f"modifier_{i}"]))
        for name, value in json.loads(str(jobs[f"settings_{i}"])).items():
            setattr(modifier, name, value)
        times = []
        for _ in range(int(jobs[f"repeats_{i}"])):
            obj.data.update()  # invalidate the evaluated copy: every repeat evaluates the modifier again
            start = time.perf_counter()
            positions = evaluate(obj)
            times.append(time.perf_counter() - start)
        results[f"positions_{i}"] = positions
        results[f"seconds_{i}"] = statistics.median(times)
    np.savez(results_path, **results)


if __name__ == "__main__":
    run_and_exit(main)
