"""A Blender mesh object read into a smoothing job (jobs.mesh.Job) and its result written back.

Shared by the Object-mode and Edit-mode operators and the command line's .blend files: every job is read
and validated before any mesh is written, so a failure leaves every mesh as it was. What a job does
between reading and writing (the core options, the run, the report) is jobs.mesh, without Blender.
"""

import numpy as np

from .. import core
from ..jobs.mesh import METHOD_LABEL, Job, deviation_map, local_result
from . import mesh_io, objects


def make_job(obj, props, extra_fixed=None):
    """Read ``obj``'s mesh into a Job, or raise InputError saying what is wrong. Reads only."""
    if obj.type != "MESH":
        raise objects.InputError(f"'{obj.name}' is a {obj.type.lower().replace('_', ' ')} object, not a mesh")
    objects.check_editable(obj)
    mesh = obj.data
    n = len(mesh.vertices)
    if n == 0:
        raise objects.InputError(f"Mesh '{mesh.name}' has no vertices: nothing to smooth")
    if len(mesh.edges) == 0:
        raise objects.InputError(
            f"Mesh '{mesh.name}' has no edges: it is a point cloud. "
            "Use Object > HC Smooth Points (object.hc_smooth_points) instead"
        )
    positions, key_block = objects.read_positions(obj)
    frame = objects.world_frame(obj)
    edges = mesh_io.read_edges(mesh)
    corner_verts, corner_edges = mesh_io.read_corners(mesh)
    corners = None
    # Every face edge shared by two faces or more: no seam was split, the welding's search (a sort) is skipped.
    seams = not (corner_edges.size and core.every_edge_shared(corner_edges, len(mesh.edges)))
    if corner_verts.size and corner_verts.size == 3 * len(mesh.polygons):
        # All triangles (scans): the faces come free; whether they close is checked with the report, off
        # this thread (input_measure).
        faces, closed, corners = corner_verts.reshape(-1, 3), None, (corner_verts, corner_edges)
    else:
        closed = core.closed_from_corners(edges, corner_verts, corner_edges)
        # Triangulated once per mesh, for the volume and the normals in the report (only the positions change).
        faces = mesh_io.read_faces(mesh, corner_verts)
        faces = core.fan_triangles(faces) if faces is not None else None
    fixed = np.zeros(n, dtype=bool) if extra_fixed is None else extra_fixed.copy()
    if props.vertex_group:
        group = obj.vertex_groups.get(props.vertex_group)
        if group is None:
            raise objects.InputError(f"Object '{obj.name}' has no vertex group '{props.vertex_group}'")
        members = mesh_io.vertex_group_members(obj, group.index)
        fixed |= ~members if props.invert_vertex_group else members
    influence = None
    if props.influence_group:
        group = obj.vertex_groups.get(props.influence_group)
        if group is None:
            raise objects.InputError(
                f"Object '{obj.name}' has no vertex group '{props.influence_group}' (the influence group)"
            )
        influence = mesh_io.vertex_group_weights(obj, group.index)
        if props.invert_influence_group:
            influence = 1.0 - influence
        np.clip(influence, 0.0, 1.0, out=influence)  # Blender keeps weights in [0, 1]; rounding may not
    return Job(
        obj=obj,
        mesh=mesh,
        positions=positions if frame is None else core.to_frame(positions, frame),
        edges=edges,
        faces=faces,
        fixed=fixed,
        closed=closed,
        corners=corners,
        seams=seams,
        key_block=key_block,
        influence=influence,
        map_names=mesh_io.deviation_names(obj) if props.deviation_map else None,
        frame=frame,
        local=None if frame is None else positions,
    )


def write_all(jobs, props):
    """Write every job's result (``write``); with Deviation Map on, every map is made (and where it goes was
    chosen when the job was read) before anything is written, so a failure leaves every mesh as it was."""
    if props.deviation_map:
        for job in jobs:
            deviation_map(job)
    for job in jobs:
        write(job, props)


def write(job, props):
    """Write a job's result: into the mesh (and the active shape key) or into a new shape key; with Deviation
    Map on, also its map as point attributes of the mesh."""
    if props.deviation_map:
        deviation = deviation_map(job)
        mesh_io.write_deviation(job.mesh, job.map_names, deviation.deviation, deviation.colors)
    before, result = local_result(job)
    if props.output == "SHAPE_KEY":
        if job.mesh.shape_keys is None:
            job.obj.shape_key_add(name="Basis", from_mix=False)
        key = job.obj.shape_key_add(name=METHOD_LABEL[props.method] + " Smooth", from_mix=False)
        mesh_io.write_shape_key(key, result)
        return
    objects.write_positions(job.obj, job.key_block, before, result)
