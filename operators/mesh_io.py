"""Bulk transfer between Blender meshes and NumPy arrays (foreach_get/foreach_set, no per-vertex Python).

Everything here reads or writes whole arrays; the operators validate first and write last, so a mesh
is written back whole or not at all.
"""

import numpy as np


def read_positions(data):
    """Positions (n, 3) float32 through the position attribute (the fast path) of a mesh or point cloud."""
    attribute = data.attributes["position"]
    buffer = np.empty(len(attribute.data) * 3, dtype=np.float32)
    attribute.data.foreach_get("vector", buffer)
    return buffer.reshape(-1, 3)


def write_positions(data, positions):
    """Write positions of a mesh (then recomputes what depends on them) or a point cloud (then tagged)."""
    data.attributes["position"].data.foreach_set("vector", np.ascontiguousarray(positions, np.float32).ravel())
    if hasattr(data, "polygons"):
        data.update()
    else:
        data.update_tag()


def read_edges(mesh):
    """Edge vertex pairs (m, 2) int32."""
    buffer = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    attribute = mesh.attributes.get(".edge_verts")
    if attribute is not None and attribute.data_type == "INT32_2D":
        attribute.data.foreach_get("value", buffer)
    else:
        mesh.edges.foreach_get("vertices", buffer)
    return buffer.reshape(-1, 2)


def read_corners(mesh):
    """Per face corner: its vertex and the edge to the next corner of its face, both int32 (Blender's
    ".corner_vert" and ".corner_edge"; plain attribute copies, unlike the face offsets)."""
    verts = np.empty(len(mesh.loops), dtype=np.int32)
    edges = np.empty(len(mesh.loops), dtype=np.int32)
    for name, prop, buffer in ((".corner_vert", "vertex_index", verts), (".corner_edge", "edge_index", edges)):
        attribute = mesh.attributes.get(name)
        if attribute is not None:
            attribute.data.foreach_get("value", buffer)
        else:
            mesh.loops.foreach_get(prop, buffer)
    return verts, edges


def read_faces(mesh, corner_verts=None):
    """Faces as core.metrics.fan_triangles takes them, None without faces: the (f, 3) corner vertices of
    an all-triangle mesh, else (offsets, corner_verts).

    Face offsets come only through the polygons' RNA (~0.1 s per million faces); a mesh with three
    corners per face is all triangles, so it needs none."""
    if not len(mesh.polygons):
        return None
    if corner_verts is None:
        corner_verts, _ = read_corners(mesh)
    if corner_verts.size == 3 * len(mesh.polygons):
        return corner_verts.reshape(-1, 3)
    starts = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    return np.append(starts, corner_verts.size), corner_verts


def read_bool_attribute(mesh, name, default=False):
    """A boolean point attribute such as ".select_vert" or ".hide_vert"; absent means all ``default``."""
    attribute = mesh.attributes.get(name)
    values = np.full(len(mesh.vertices), default, dtype=bool)
    if attribute is not None and attribute.domain == "POINT" and attribute.data_type == "BOOLEAN":
        attribute.data.foreach_get("value", values)
    return values


def read_shape_key(key_block):
    buffer = np.empty(len(key_block.data) * 3, dtype=np.float32)
    key_block.data.foreach_get("co", buffer)
    return buffer.reshape(-1, 3)


def write_shape_key(key_block, positions):
    key_block.data.foreach_set("co", np.ascontiguousarray(positions, np.float32).ravel())


def vertex_group_members(obj, group_index):
    """Boolean mask of the vertices with weight > 0 in the vertex group."""
    return vertex_group_weights(obj, group_index) > 0.0


def vertex_group_weights(obj, group_index):
    """The vertex group's weights, float32, 0 where a vertex is not in the group.

    Blender has no bulk accessor for weights (a Python loop costs ~1 s per million vertices), but
    Geometry Nodes read a vertex group as a named attribute: a throw-away object sharing the mesh,
    with a node group that stores the weights as a float attribute, is evaluated and the attribute
    read in bulk (~10 ms per million vertices). Nothing of the user's data changes; the loop remains
    the fallback where that is not possible.
    """
    name = obj.vertex_groups[group_index].name
    if len(obj.data.vertices) >= _BULK_MINIMUM and obj.data.attributes.get(name) is None:
        try:
            return _weights_through_geometry_nodes(obj.data, name)
        except (RuntimeError, KeyError, AttributeError, TypeError):  # e.g. a read-only scene collection
            pass
    return _vertex_group_weights_loop(obj.data, group_index)


_BULK_MINIMUM = 2_000  # below this the loop is as fast as setting up an evaluation
_WEIGHT_ATTRIBUTE = "hc_smooth_weight"


def _vertex_group_weights_loop(mesh, group_index):
    weights = np.zeros(len(mesh.vertices), dtype=np.float32)
    for vertex in mesh.vertices:
        for element in vertex.groups:
            if element.group == group_index:
                weights[vertex.index] = element.weight
                break
    return weights


def _weights_through_geometry_nodes(mesh, group_name):
    import bpy

    tree = bpy.data.node_groups.new("HC Smooth weights (temporary)", "GeometryNodeTree")
    carrier = None
    try:
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        group_input, group_output = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
        weight = tree.nodes.new("GeometryNodeInputNamedAttribute")
        weight.data_type = "FLOAT"
        weight.inputs["Name"].default_value = group_name
        store = tree.nodes.new("GeometryNodeStoreNamedAttribute")
        store.data_type, store.domain = "FLOAT", "POINT"
        store.inputs["Name"].default_value = _WEIGHT_ATTRIBUTE
        tree.links.new(group_input.outputs[0], store.inputs["Geometry"])
        tree.links.new(weight.outputs["Attribute"], store.inputs["Value"])
        tree.links.new(store.outputs["Geometry"], group_output.inputs[0])

        carrier = bpy.data.objects.new("HC Smooth weights (temporary)", mesh)
        carrier.modifiers.new("weights", "NODES").node_group = tree
        bpy.context.scene.collection.objects.link(carrier)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        depsgraph.update()
        evaluated = carrier.evaluated_get(depsgraph).data
        if len(evaluated.vertices) != len(mesh.vertices):
            raise RuntimeError("evaluated mesh does not match")
        weights = np.empty(len(evaluated.vertices), dtype=np.float32)
        evaluated.attributes[_WEIGHT_ATTRIBUTE].data.foreach_get("value", weights)
        return weights
    finally:
        if carrier is not None:
            bpy.data.objects.remove(carrier)
        bpy.data.node_groups.remove(tree)
