"""Bulk transfer between Blender meshes and NumPy arrays (foreach_get/foreach_set, no per-vertex Python).

Everything here reads or writes whole arrays; the operators validate first and write last, so a mesh
is written back whole or not at all.
"""

import contextlib
from dataclasses import dataclass

import numpy as np

from ..jobs.mesh import DEVIATION_ATTRIBUTE, DEVIATION_COLOR_ATTRIBUTE


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
    """Faces as core.fan_triangles takes them, None without faces: the (f, 3) corner vertices of
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


_MAP_TYPES = {DEVIATION_ATTRIBUTE: "FLOAT", DEVIATION_COLOR_ATTRIBUTE: "FLOAT_COLOR"}


@dataclass(frozen=True)
class DeviationNames:
    """Where a mesh's deviation map goes (``deviation_names``)."""

    value: str  # the float point attribute of the map
    color: str  # its colours, a float colour point attribute
    # The mesh has no colour attributes of its own: the map's colours become the active ones (what Solid shading's
    # Attribute colour shows) and the render colours (what renders and exporters use). Else the user's choice stays.
    shown: bool

    @property
    def usual(self):
        return (self.value, self.color) == (DEVIATION_ATTRIBUTE, DEVIATION_COLOR_ATTRIBUTE)


def deviation_names(obj):
    """Where ``obj``'s mesh takes a deviation map; reads only. Each of the two attributes goes to the first of
    "hc_deviation", "hc_deviation.001", "hc_deviation.002", ... (as Blender numbers names) that no vertex group
    has and that no attribute has, or an earlier map only: a point attribute of the map's type under one of
    those names (the add-on made it; it is overwritten). What the user made (a UV map, an attribute of another
    type or domain, a vertex group, whose names Geometry Nodes read as attributes) keeps its name and data."""
    mesh = obj.data
    groups = {group.name for group in obj.vertex_groups}
    value, color = (_map_name(mesh, groups, base) for base in (DEVIATION_ATTRIBUTE, DEVIATION_COLOR_ATTRIBUTE))
    own = [attribute for attribute in mesh.color_attributes if _map_base(attribute) is None]
    return DeviationNames(value, color, shown=not own)


def _map_name(mesh, groups, base):
    def free(name):
        attribute = mesh.attributes.get(name)
        return name not in groups and (attribute is None or _map_base(attribute) == base)

    return next(name for name in _numbered(base) if free(name))


def _numbered(base):
    yield base
    count = 1
    while True:
        yield f"{base}.{count:03d}"
        count += 1


def _map_base(attribute):
    """The map attribute ("hc_deviation" or "hc_deviation_color") that ``attribute`` holds an earlier one of,
    None for anything else: its name is the base or a numbered one, on points, of the base's type."""
    base, dot, number = attribute.name.rpartition(".")
    if not (dot and number.isdigit() and len(number) >= 3):
        base = attribute.name
    if base not in _MAP_TYPES or attribute.domain != "POINT" or attribute.data_type != _MAP_TYPES[base]:
        return None
    return base


def write_deviation(mesh, names, deviation, colors):
    """Store a deviation map as the point attributes ``names`` (a DeviationNames of this mesh); on a mesh
    without colours of its own (``names.shown``) its colours become the active and the render colours, else the
    user's choice of both stays as it was. ``colors``: linear RGBA (n, 4), written through the float colour's
    fast path (the sRGB one converts per value: ~50 times slower)."""
    values = _attribute(mesh, names.value, "FLOAT")
    values.data.foreach_set("value", np.ascontiguousarray(deviation, np.float32))
    color = _attribute(mesh, names.color, "FLOAT_COLOR")
    color.data.foreach_set("color", np.ascontiguousarray(colors, np.float32).ravel())
    if names.shown:
        mesh.color_attributes.active_color_name = names.color  # what Solid shading's Attribute colour shows
        mesh.color_attributes.default_color_name = names.color  # the one renders and exports use


def _attribute(mesh, name, data_type):
    """The point attribute ``name`` of ``data_type``, made where the mesh has none of that name."""
    attribute = mesh.attributes.get(name)
    return attribute if attribute is not None else mesh.attributes.new(name, data_type, "POINT")


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
    Geometry Nodes read a vertex group as a named attribute: a throw-away object with a copy of the
    mesh, and a node group that stores the weights as a float attribute, is evaluated and the attribute
    read in bulk (~10 ms per million vertices). An attribute of the group's name comes first in that
    lookup, built-in ones included whether the mesh has them or not ("id", "material_index",
    "sharp_edge", ... read as zeros), so the copy's group is renamed first. The copy shares the mesh's
    arrays (copy-on-write: ~0.2 ms and no memory for a million vertices). Nothing of the user's data
    changes; the loop remains the fallback where that is not possible.
    """
    if len(obj.data.vertices) >= _BULK_MINIMUM:
        try:
            return _weights_through_geometry_nodes(obj.data, group_index)
        except (RuntimeError, KeyError, AttributeError, TypeError):  # e.g. a read-only scene collection
            pass
    return _vertex_group_weights_loop(obj.data, group_index)


def group_read_by_name(obj, group_index):
    """Whether a Geometry Nodes modifier's field input (the HC Smooth modifier's Fixed Group, Influence) reads
    this vertex group by its name, or an attribute of that name instead (Blender 4.x: built-in ones such as
    "id" or "sharp_edge"; the mesh's own, such as a UV map): the weights read by the name are compared with
    the group's own."""
    by_name = _weights_through_geometry_nodes(obj.data, group_index, rename=False)
    return np.array_equal(by_name, vertex_group_weights(obj, group_index))


def geometry_nodes_move_vertices(obj):
    """Whether a Geometry Nodes modifier can move the vertices of ``obj``'s mesh: Blender 5.2 writes Set
    Position into a vertex group named "position" instead (and Edge Vertices read it), which leaves every
    such modifier, HC Smooth's too, with a wrong result. A throw-away copy's vertices are all set to one
    point and read back."""
    if obj.vertex_groups.get("position") is None or not len(obj.data.vertices):
        return True  # nothing of that name: the positions are the position attribute
    target = (0.25, -0.5, 1.75)

    def build(tree, group_input, group_output):
        move, point = tree.nodes.new("GeometryNodeSetPosition"), tree.nodes.new("ShaderNodeCombineXYZ")
        for socket, value in zip(point.inputs, target):
            socket.default_value = value
        tree.links.new(point.outputs[0], move.inputs["Position"])  # its own value is the Position field
        tree.links.new(group_input.outputs["Geometry"], move.inputs["Geometry"])
        tree.links.new(move.outputs["Geometry"], group_output.inputs[0])

    with _evaluated_copy(obj.data, build) as (_, evaluated):
        moved = read_positions(evaluated)
    return bool(np.all(moved == np.array(target, dtype=np.float32)))


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


def _weights_through_geometry_nodes(mesh, group_index, rename=True):
    """The weights of the mesh's vertex group ``group_index`` as a Geometry Nodes modifier's field input reads
    them by name (as the HC Smooth modifier reads its groups): under a name no attribute has (``rename``), else
    under the group's own."""
    from ..nodes import inputs

    def build(tree, group_input, group_output):
        tree.interface.new_socket("Weight", in_out="INPUT", socket_type="NodeSocketFloat")
        store = tree.nodes.new("GeometryNodeStoreNamedAttribute")
        store.data_type, store.domain = "FLOAT", "POINT"
        store.inputs["Name"].default_value = _WEIGHT_ATTRIBUTE
        tree.links.new(group_input.outputs["Geometry"], store.inputs["Geometry"])
        tree.links.new(group_input.outputs["Weight"], store.inputs["Value"])
        tree.links.new(store.outputs["Geometry"], group_output.inputs[0])

    def prepare(carrier, modifier):
        group = carrier.vertex_groups[group_index]  # the copy's: renaming it leaves the user's as it is
        if rename:
            taken = {attribute.name for attribute in carrier.data.attributes} | {g.name for g in carrier.vertex_groups}
            group.name = next(name for name in _unused_names() if name not in taken)
        inputs.set_input_attribute(modifier, "Weight", group.name)

    with _evaluated_copy(mesh, build, prepare) as (_, evaluated):
        weights = np.empty(len(evaluated.vertices), dtype=np.float32)
        evaluated.attributes[_WEIGHT_ATTRIBUTE].data.foreach_get("value", weights)
    return weights


@contextlib.contextmanager
def _evaluated_copy(mesh, build, prepare=None):
    """Evaluate a throw-away Geometry Nodes modifier on a throw-away object holding a copy of ``mesh``; yields
    (carrier, evaluated mesh), then removes all three. ``build(tree, group_input, group_output)`` fills the
    node tree; ``prepare(carrier, modifier)`` sets up the copy and the modifier before the evaluation."""
    import bpy

    tree = bpy.data.node_groups.new("HC Smooth (temporary)", "GeometryNodeTree")
    copy = mesh.copy()
    carrier = None
    try:
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        group_input, group_output = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
        build(tree, group_input, group_output)
        carrier = bpy.data.objects.new("HC Smooth (temporary)", copy)
        modifier = carrier.modifiers.new("HC Smooth (temporary)", "NODES")
        modifier.node_group = tree
        if prepare is not None:
            prepare(carrier, modifier)
        bpy.context.scene.collection.objects.link(carrier)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        depsgraph.update()
        evaluated = carrier.evaluated_get(depsgraph).data
        if len(evaluated.vertices) != len(mesh.vertices):
            raise RuntimeError("evaluated mesh does not match")
        yield carrier, evaluated
    finally:
        if carrier is not None:
            bpy.data.objects.remove(carrier)
        bpy.data.meshes.remove(copy)
        bpy.data.node_groups.remove(tree)


def _unused_names():
    """Names for the copy's group that no built-in attribute has."""
    yield "hc_smooth_group"
    count = 1
    while True:
        yield f"hc_smooth_group_{count}"
        count += 1
