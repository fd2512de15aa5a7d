"""The "HC Smooth" Geometry Nodes group behind the HC Smooth modifier, built by code.

Built by code rather than shipped as a .blend asset: one builder serves every supported Blender
(4.2 LTS to 5.2 LTS) and handles the node API differences in one place, where a .blend saved by one
version is read by older ones only as far as they understand it; the nodes are reviewed and tested
like the rest of the add-on. A file that uses the modifier stores the group, so it evaluates the
same in a Blender without the add-on.

The group runs the paper's simultaneous step (Vollmer, Mencl, Müller 1999: sections 3.1-3.3 and
Algorithm 1) with the umbrella operator T x_i = mean_{j∈adj(i)} x_j taken on the edge domain: the
edge field x(v1) + x(v2), read on points (Blender averages it over each vertex's edges), is
x_i + T x_i. HC per movable vertex, in the form of core/smoothing.py:

    s = α o + (1-α) q,   w = (1-β) (T q - s)  (w = 0 on fixed vertices),   p = s + w - T w

T w is taken by writing w into the positions for a moment (q waits in a captured attribute, and s is
taken again from it), so that both umbrellas read the edges' end positions (Edge Vertices) instead of
gathering an attribute per edge end (Evaluate at Index), which costs two to three times as much
(bench/results/2026-11-25-modifier.md, "Where the time goes"). The Laplacian with the original point
(p = α o + (1-α) T q) runs in the same Repeat zone. Plain Laplacian (p = T q) and the central point
(p = α q + (1-α) T q) need no o, so one Blur Attribute node runs all their iterations: with weight W_i
on vertex i's neighbours, Blur gives (q_i + W_i Σ_j q_j) / (1 + W_i |adj(i)|), which is the central step for
W_i = (1-α) / (α |adj(i)|), the plain one as α -> 0, and q_i for W_i = 0.

Fixed vertices (Fixed Group, Pin Boundary, and vertices without edges, as in core) keep q exactly:
they get Blur weight 0 and are left out of Set Position, and in HC take back their original position.

Painted influence λ (the Influence input, a vertex group's weights) is core's influence=: after each
iteration a vertex takes q + λ (p - q) instead of p, q itself where λ = 0. For the Blur methods that
is the central step with a per-vertex weight (see build()); the Repeat zone mixes p and q only when
some vertex has λ < 1, so without a painted group it evaluates the unweighted step alone.

The Deviation Limit r is core's max_deviation= in world space, as the operators take it (they run core on the
world-space shape, core.mesh.world): every iteration ends with p = o + d min(1, r / |L d|), d = p - o, L the 3x3
part of the object's world matrix (Object Info on the Self Object), after the influence (0 = no limit). The
steps themselves are linear in the positions, so they are the same in object and world space. Plain and
central Laplacian then run in the Repeat zone too (one Blur node cannot stop after each iteration); without a
limit the zone is built without it. Reading the object's matrix makes Blender evaluate the group again when
the object's transform changes.

Deviation Map stores each vertex's signed move along its input normal as the point attribute hc_deviation, as
the mesh operators do (core.normal_deviation), in world space: the input's positions and area-weighted vertex
normals (taken through L's inverse transpose, as normals transform) are captured first and carried to the end,
where L (position - start) . normal is stored. Off, neither is evaluated.

Guards (the modifier cannot write garbage, whoever sets its inputs: the panel, a script writing the modifier's
ID properties, NaN included): each single-value input is clamped to its range inside the tree by comparisons
(a Clamp or Minimum node passes NaN on); a NaN Alpha, Beta or Deviation Limit, HC with Beta below 0.5 for more
than SAFE_HC_STEPS iterations, and a result that is not finite or has blown up (core's test: a bounding box
BLOW_UP_FACTOR times the input's) pass the mesh through unchanged. Each case says why in the modifier's
Warnings panel (the Warning node, Blender 4.3 and later; on 4.2 the pass-through alone).
"""

import bpy

from .. import settings_spec
from ..core import BLOW_UP_FACTOR

GROUP_NAME = "HC Smooth"
# Bump whenever the nodes or the interface change: an older group in a file is then rebuilt in place.
VERSION = 6
DEVIATION_ATTRIBUTE = "hc_deviation"  # the Deviation Map's output, as the mesh operators store it
NAME_TAKEN = (
    f"Deviation Map not stored: the mesh already has an attribute '{DEVIATION_ATTRIBUTE}' (yours, a UV map or "
    "vertex group of that name, or an earlier map); rename or remove it"
)
VERSION_KEY = "hc_smooth_version"

# Blur weight standing in for "only the neighbours" (plain Laplacian): the centre's own share is
# 2^-40 of theirs, far below single-precision rounding, and W |q| stays finite up to |q| ~ 1e26.
NEIGHBOURS_ONLY = 2.0**-40

# HC with Beta below 0.5 grows without bound (on an alternating pattern each step multiplies it by up to 3 - α),
# so it is refused beyond this many iterations. Within them it cannot reach the blow-up test: an iteration
# keeps each coordinate within 3 times its largest distance from the input box's centre (T averages; b and T b
# are at most twice that distance; the influence and the limit mix with q and o), so 2 iterations leave the
# bounding box at most 3² = 9 times the input's. With Beta >= 0.5 the step's factors lie in [-1, 1] for every α
# in [0, 1]: no growth, though only α > 0 and β > 0.5 are proven to converge (paper, Theorem 5.2).
SAFE_HC_STEPS = 2
LARGEST_FINITE = 3.0e38  # below float32's largest: a sum of |coordinates| beyond it is infinite or NaN
PASSED_THROUGH = "the mesh is passed through unchanged"

METHOD_ITEMS = tuple((choice.label, choice.description) for choice in settings_spec.METHOD.items)
HC, LAPLACIAN, CENTRAL, ORIGINAL = range(4)  # the menu's values, in settings_spec.METHOD's order
# settings_spec identifier ("LAPLACIAN_CENTRAL") -> the menu item's name ("Laplacian, Central Point")
METHOD_NAMES = {choice.identifier: choice.label for choice in settings_spec.METHOD.items}


# --- the group's interface: one input per setting of settings_spec.MODIFIER -----------------------------------


def input_name(setting):
    """The input of a setting of settings_spec.MODIFIER: named by the setting's label ("Fixed Group")."""
    return setting.label


SOCKET_TYPES = {
    "enum": "NodeSocketMenu",
    "float": "NodeSocketFloat",
    "int": "NodeSocketInt",
    "bool": "NodeSocketBool",
    "string": "NodeSocketFloat",  # a vertex group's name: the input reads that group's weights
}
# The vertex-group settings as per-vertex inputs (the rest are single values): what the input says and holds.
FIELDS = {
    settings_spec.VERTEX_GROUP.name: dict(
        description="Vertices with a weight above 0 stay fixed: pick a vertex group with the button on the right",
        default=0.0,
        min=0.0,
        max=1.0,
    ),
    settings_spec.INFLUENCE_GROUP.name: dict(
        description="How far each vertex moves in every iteration (0 = stays, 1 = the full step): pick a "
        "vertex group with the button on the right",
        default=1.0,
        min=0.0,
        max=1.0,
    ),
}


def _interface(tree):
    interface = tree.interface
    interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    sockets = {}
    for setting in settings_spec.MODIFIER:
        name, socket_type = input_name(setting), SOCKET_TYPES[setting.kind]
        spec = FIELDS.get(setting.name) or dict(
            description=setting.description, default=setting.default, min=setting.min, max=setting.max
        )
        socket = interface.new_socket(name, in_out="INPUT", socket_type=socket_type, description=spec["description"])
        if socket_type != "NodeSocketMenu":  # a menu's default is set once its items exist
            socket.default_value = spec["default"]
        if spec["min"] is not None:
            socket.min_value = spec["min"]
        if spec["max"] is not None:
            socket.max_value = spec["max"]
        if setting.subtype and hasattr(socket, "subtype"):  # Deviation Limit in scene units
            socket.subtype = setting.subtype
        if setting.name not in FIELDS:
            _single_value(socket)
        sockets[name] = socket
    return sockets


def _single_value(socket):
    """A setting, not a field: no attribute toggle beside it in the modifier."""
    if hasattr(socket, "structure_type"):  # Blender 4.5+
        socket.structure_type = "SINGLE"
    elif hasattr(socket, "force_non_field"):
        socket.force_non_field = True


# --- building nodes --------------------------------------------------------------------------------------


class _Tree:
    """Small helpers over a node tree: add nodes, and feed a socket either a link or a constant."""

    def __init__(self, tree):
        self.tree = tree
        self.count = 0

    def node(self, idname, **attributes):
        node = self.tree.nodes.new(idname)
        for key, value in attributes.items():
            setattr(node, key, value)
        node.location = (180 * (self.count % 12), -160 * (self.count // 12))  # a grid, for inspection
        self.count += 1
        return node

    def feed(self, socket, value):
        if isinstance(value, bpy.types.NodeSocket):
            self.tree.links.new(value, socket)
        else:
            socket.default_value = value

    def math(self, operation, a, b=0.0, c=None):
        node = self.node("ShaderNodeMath", operation=operation)
        for socket, value in zip(node.inputs, (a, b) if c is None else (a, b, c)):
            self.feed(socket, value)
        return node.outputs[0]

    def vector(self, operation, a, b):
        node = self.node("ShaderNodeVectorMath", operation=operation)
        self.feed(node.inputs[0], a)
        self.feed(node.inputs[1], b)
        return node.outputs[0]

    def scale(self, vector, factor):
        node = self.node("ShaderNodeVectorMath", operation="SCALE")
        self.feed(node.inputs[0], vector)
        self.feed(node.inputs["Scale"], factor)
        return node.outputs["Vector"]

    def add(self, a, b):
        return self.vector("ADD", a, b)

    def subtract(self, a, b):
        return self.vector("SUBTRACT", a, b)

    def boolean(self, operation, a, b=False):
        node = self.node("FunctionNodeBooleanMath", operation=operation)
        self.feed(node.inputs[0], a)
        if operation != "NOT":  # NOT has one input (Blender 5 lists no hidden second one)
            self.feed(node.inputs[1], b)
        return node.outputs[0]

    def switch(self, input_type, condition, false, true):
        node = self.node("GeometryNodeSwitch", input_type=input_type)
        self.feed(node.inputs["Switch"], condition)
        self.feed(node.inputs["False"], false)
        self.feed(node.inputs["True"], true)
        return node.outputs[0]

    def on_domain(self, value, domain, data_type):
        """Evaluate on Domain: ``value`` taken on ``domain``, read in the caller's (Blender interpolates)."""
        node = self.node("GeometryNodeFieldOnDomain", domain=domain, data_type=data_type)
        self.feed(node.inputs[0], value)
        return node.outputs[0]

    def capture(self, geometry, items):
        """Capture Attribute on points, one item per (socket type, name, field); (geometry, [fields])."""
        node = self.node("GeometryNodeCaptureAttribute", domain="POINT")
        for socket_type, name, value in items:
            node.capture_items.new(socket_type, name)
            self.feed(node.inputs[name], value)
        self.feed(node.inputs["Geometry"], geometry)
        return node.outputs["Geometry"], [node.outputs[name] for _, name, _ in items]

    def set_position(self, geometry, position, selection=None):
        node = self.node("GeometryNodeSetPosition")
        self.feed(node.inputs["Geometry"], geometry)
        self.feed(node.inputs["Position"], position)
        # Set Position writes position + offset: x + (-0.0) is x for every x, where + 0.0 makes -0.0 into 0.0.
        node.inputs["Offset"].default_value = (-0.0, -0.0, -0.0)
        if selection is not None:
            self.feed(node.inputs["Selection"], selection)
        return node.outputs["Geometry"]

    def clamp(self, value, low=0.0, high=1.0):
        """``value`` within [low, high] (high None: no upper limit), NaN to ``low``. By comparisons, which are
        false for NaN, where a Clamp or Minimum node passes NaN on; a value inside keeps its bits."""
        value = self.switch("FLOAT", self.math("GREATER_THAN", value, low), low, value)
        if high is None:
            return value
        return self.switch("FLOAT", self.math("LESS_THAN", value, high), high, value)

    def is_number(self, value):
        """False for NaN only (every number is above 0 or below 1)."""
        return self.boolean("OR", self.math("GREATER_THAN", value, 0.0), self.math("LESS_THAN", value, 1.0))

    def outside(self, value, low, high=None):
        """A number below ``low`` or above ``high`` (None: no upper limit); False for NaN."""
        below = self.math("LESS_THAN", value, low)
        return below if high is None else self.boolean("OR", below, self.math("GREATER_THAN", value, high))

    def warning(self, show, message, kind="ERROR"):
        """A line in the modifier's Warnings panel while ``show`` is true; returns ``show`` (a Warning node's
        output is its input). Blender 4.2 has no Warning node: ``show`` alone."""
        if not hasattr(bpy.types, "GeometryNodeWarning"):
            return show
        node = self.node("GeometryNodeWarning", warning_type=kind)
        self.feed(node.inputs["Show"], show)
        node.inputs["Message"].default_value = message
        return node.outputs["Show"]

    def any_of(self, conditions):
        result = conditions[0]
        for condition in conditions[1:]:
            result = self.boolean("OR", result, condition)
        return result

    def statistic(self, geometry, value, output):
        """``output`` ("Min", "Max") of a float field over the points of ``geometry``: a single value."""
        node = self.node("GeometryNodeAttributeStatistic", data_type="FLOAT", domain="POINT")
        self.feed(node.inputs["Geometry"], geometry)
        self.feed(node.inputs["Attribute"], value)
        return node.outputs[output]

    def diagonal(self, low, high):
        return self.node_output("ShaderNodeVectorMath", "Value", operation="LENGTH", inputs=[self.subtract(high, low)])

    def node_output(self, idname, output, inputs=(), **attributes):
        node = self.node(idname, **attributes)
        for socket, value in zip(node.inputs, inputs):
            self.feed(socket, value)
        return node.outputs[output]

    def position(self):
        return self.node("GeometryNodeInputPosition").outputs[0]

    def world(self, direction, transform):
        """A direction (a move, a vector between points) through ``transform``'s 3x3 part."""
        return self.node_output("FunctionNodeTransformDirection", "Direction", inputs=[direction, transform])

    def umbrella_of_positions(self):
        """T q on points: the mean of the neighbours' positions (a vertex without edges gets -q; it is fixed)."""
        ends = self.node("GeometryNodeInputMeshEdgeVertices")
        pair_sum = self.add(ends.outputs["Position 1"], ends.outputs["Position 2"])
        return self.subtract(self.on_domain(pair_sum, "EDGE", "FLOAT_VECTOR"), self.position())


def build(tree):
    """Fill an empty Geometry Nodes tree with the HC Smooth group."""
    sockets = _interface(tree)
    t = _Tree(tree)
    inputs = t.node("NodeGroupInput").outputs
    group_output = t.node("NodeGroupOutput")

    def value(setting):
        return inputs[input_name(setting)]

    is_method = _method_switch(t, value(settings_spec.METHOD))
    alpha, beta, iterations, limit, refused = _checked_inputs(t, value, is_method(HC))

    # The object's world matrix: the limit and the map measure lengths in world space.
    info = t.node("GeometryNodeObjectInfo", transform_space="ORIGINAL")
    t.feed(info.inputs["Object"], t.node("GeometryNodeSelfObject").outputs[0])
    transform = info.outputs["Transform"]

    # With Deviation Map on, the input's positions and normals ride along (captured) to the end.
    deviation_map = value(settings_spec.MODIFIER_DEVIATION_MAP)
    geometry, start_position, start_normal = _start_of_map(t, inputs["Geometry"], deviation_map, transform)

    movable, degree = _movable(t, value)
    influence = _influence(t, value)
    blurred = _blurred(t, geometry, (alpha, iterations, influence, movable, degree), is_method)
    iterated, limited = _repeat_zone(
        t, geometry, (alpha, beta, iterations, limit, transform), movable, influence, is_method
    )
    uses_blur = t.boolean("AND", t.boolean("OR", is_method(LAPLACIAN), is_method(CENTRAL)), t.boolean("NOT", limited))
    smoothed = t.switch("GEOMETRY", uses_blur, iterated, blurred)
    result = _guarded(t, geometry, smoothed, refused)
    t.feed(
        group_output.inputs["Geometry"],
        _deviation_map(t, result, deviation_map, start_position, start_normal, transform),
    )

    sockets[input_name(settings_spec.METHOD)].default_value = METHOD_NAMES[settings_spec.METHOD.default]
    return sockets


def _method_switch(t, method_input):
    """is_method(number): a node giving 1.0 where the group's method is that number, else 0.0."""
    # The method as its number. A new Menu Switch has two items (numbers 0, 1): renamed, not replaced,
    # so the items are numbered 0..3 in settings_spec's order and a 4.x script can set the number.
    # A number outside the menu (a script can write one in 4.x) reads as 0, HC.
    menu = t.node("GeometryNodeMenuSwitch", data_type="INT")
    while len(menu.enum_items) < len(METHOD_ITEMS):
        menu.enum_items.new("")
    for number, (item, (name, description)) in enumerate(zip(menu.enum_items, METHOD_ITEMS)):
        item.name, item.description = name, description
        menu.inputs[name].default_value = number
    t.feed(menu.inputs[0], method_input)
    method = menu.outputs[0]

    def is_method(number):  # 1.0 or 0.0; COMPARE's third input, the tolerance, is 0.5 by default
        return t.math("COMPARE", method, float(number))

    return is_method


def _movable(t, value):
    """(movable, degree): the vertices that move, and each vertex's neighbour count."""
    # Who moves: outside the fixed group (inside it, inverted), not on a pinned boundary, with neighbours.
    in_group = t.math("GREATER_THAN", value(settings_spec.VERTEX_GROUP), 0.0)
    fixed = t.boolean("XOR", in_group, value(settings_spec.INVERT_VERTEX_GROUP))
    edge_faces = t.node("GeometryNodeInputMeshEdgeNeighbors").outputs["Face Count"]
    boundary_edge = t.math("COMPARE", edge_faces, 1.0)  # an edge of exactly one face (loose edges: none)
    on_boundary = t.math("GREATER_THAN", t.on_domain(boundary_edge, "EDGE", "FLOAT"), 0.0)
    fixed = t.boolean("OR", fixed, t.boolean("AND", value(settings_spec.PIN_BOUNDARY), on_boundary))
    degree = t.node("GeometryNodeInputMeshVertexNeighbors").outputs["Vertex Count"]
    fixed = t.boolean("OR", fixed, t.math("LESS_THAN", degree, 0.5))
    movable = t.boolean("NOT", fixed)
    return movable, degree


def _influence(t, value):
    """Each vertex's share of a step (the painted influence)."""
    # The painted influence, as core takes it: the group's weights (inverted: 1 - weight) clipped to [0, 1]
    # (NaN, which an attribute can hold: 0).
    painted = value(settings_spec.INFLUENCE_GROUP)
    return t.clamp(
        t.switch("FLOAT", value(settings_spec.INVERT_INFLUENCE_GROUP), painted, t.math("SUBTRACT", 1.0, painted))
    )


def _blurred(t, geometry, settings, is_method):
    """The plain and central Laplacian without a limit; ``settings``: (alpha, iterations, influence, movable,
    degree)."""
    alpha, iterations, influence, movable, degree = settings
    # Plain and central Laplacian without a limit: one Blur Attribute, all iterations (weights as in the
    # module's docstring). Influence λ makes the step the central one with a' = a + (1 - a)(1 - λ):
    # a' q + (1 - a') T q is q + λ (p - q). Where λ = 1 this is the same arithmetic as without influence.
    a = t.math("MULTIPLY", alpha, is_method(CENTRAL))  # 0 for plain
    one_minus_a = t.math("SUBTRACT", 1.0, a)
    kept = t.math("MULTIPLY_ADD", one_minus_a, t.math("SUBTRACT", 1.0, influence), a)  # a'
    moved = t.math("MULTIPLY", influence, one_minus_a)  # 1 - a'
    weight = t.math("DIVIDE", moved, t.math("MULTIPLY_ADD", kept, degree, NEIGHBOURS_ONLY))
    blur = t.node("GeometryNodeBlurAttribute", data_type="FLOAT_VECTOR")
    t.feed(blur.inputs[0], t.position())
    t.feed(blur.inputs["Iterations"], iterations)
    blur_weight = t.math("MULTIPLY", weight, movable)
    t.feed(blur.inputs["Weight"], blur_weight)
    # Blur gives q + 0 where the weight is 0, which turns -0.0 into 0.0: those vertices keep q itself.
    blurred = t.set_position(geometry, blur.outputs[0], t.math("GREATER_THAN", blur_weight, 0.0))
    return blurred


def _repeat_zone(t, geometry, settings, movable, influence, is_method):
    """(the iterated geometry, whether a limit is on): HC and the Laplacians step by step; ``settings``:
    (alpha, beta, iterations, limit, transform)."""
    alpha, beta, iterations, limit, transform = settings
    # Every method with a Deviation Limit, and HC and the original point always: a Repeat zone of simultaneous steps.
    position = t.position()
    start, (original, movable, influence) = t.capture(
        geometry,
        [("VECTOR", "Original", position), ("BOOLEAN", "Movable", movable), ("FLOAT", "Influence", influence)],
    )
    # A single value: whether any vertex takes less than the full step. If none does, the steps below are
    # built without the weighting (a Switch on a single value evaluates only the side it picks).
    partly = t.math("LESS_THAN", t.statistic(start, influence, "Min"), 1.0)

    def weighted(p, q):
        """q + λ (p - q) as core computes it, λ the influence: that share of the iteration's move from q to p;
        p itself where λ = 1 and q itself where λ = 0, bit for bit."""
        share = t.add(q, t.scale(t.subtract(p, q), influence))
        share = t.switch("VECTOR", t.math("GREATER_THAN", influence, 0.0), q, share)
        share = t.switch("VECTOR", t.math("LESS_THAN", influence, 1.0), p, share)
        return t.switch("VECTOR", partly, p, share)

    limited = t.math("GREATER_THAN", limit, 0.0)  # a single value: the limit's nodes are evaluated only if on

    def bounded(p):
        """The Deviation Limit r as core applies it in world space: p = o + d r / |L d| where |L d| > r (d = p - o,
        L the object's 3x3 transform), else p itself: the world-space ball's point on the line from o to p."""
        away = t.subtract(p, original)
        length = t.node_output("ShaderNodeVectorMath", "Value", operation="LENGTH", inputs=[t.world(away, transform)])
        projected = t.add(original, t.scale(away, t.math("DIVIDE", limit, length)))
        return t.switch("VECTOR", limited, p, t.switch("VECTOR", t.math("GREATER_THAN", length, limit), p, projected))

    repeat_in = t.node("GeometryNodeRepeatInput")
    repeat_out = t.node("GeometryNodeRepeatOutput")
    repeat_in.pair_with_output(repeat_out)
    t.feed(repeat_in.inputs["Iterations"], iterations)
    t.feed(repeat_in.inputs["Geometry"], start)
    current = repeat_in.outputs["Geometry"]

    q = t.position()
    tq = t.umbrella_of_positions()
    # The Laplacian steps: a X + (1 - a) T q with X = o (original point) or q (central), a = 0 for plain.
    a = t.math("MULTIPLY", alpha, t.math("SUBTRACT", 1.0, is_method(LAPLACIAN)))
    pulled_to = t.switch("VECTOR", is_method(CENTRAL), original, q)
    laplacian_step = t.add(t.scale(pulled_to, a), t.scale(tq, t.math("SUBTRACT", 1.0, a)))
    laplacian = t.set_position(current, bounded(weighted(laplacian_step, q)), movable)

    one_minus_alpha = t.math("SUBTRACT", 1.0, alpha)

    def anchor(q):
        """s = α o + (1-α) q."""
        return t.add(t.scale(original, alpha), t.scale(q, one_minus_alpha))

    keep = t.math("MULTIPLY", t.math("SUBTRACT", 1.0, beta), movable)
    w = t.scale(t.subtract(tq, anchor(q)), keep)
    with_q, (q_kept,) = t.capture(current, [("VECTOR", "Start", q)])  # q, while the positions carry w
    carrying_w = t.set_position(with_q, w)  # every vertex: T w below reads the neighbours' w, 0 if fixed
    hc_step = t.subtract(t.add(anchor(q_kept), t.position()), t.umbrella_of_positions())  # s + w - T w
    hc_step = bounded(weighted(hc_step, q_kept))  # influence scales the move, not w: such vertices stay in V_var
    hc = t.set_position(carrying_w, t.switch("VECTOR", movable, original, hc_step))  # fixed: o = q, exactly

    t.feed(repeat_out.inputs["Geometry"], t.switch("GEOMETRY", is_method(HC), laplacian, hc))
    return repeat_out.outputs["Geometry"], limited


def _start_of_map(t, geometry, on, transform):
    """(geometry, position, normal): the input with its positions and its unit area-weighted vertex normals in
    world space (core's on the world-space shape: the faces' normals times their areas, summed on the vertices,
    through ``transform``'s inverse transpose, normalised; 0 without a face) captured where ``on`` (a single
    value: the capture is evaluated only then), else the input as it is."""
    face = t.node("GeometryNodeInputNormal").outputs[0]
    area = t.node("GeometryNodeInputMeshFaceArea").outputs[0]
    summed = t.on_domain(t.scale(face, area), "FACE", "FLOAT_VECTOR")
    inverse = t.node_output("FunctionNodeInvertMatrix", "Matrix", inputs=[transform])
    normals = t.node_output("FunctionNodeTransposeMatrix", "Matrix", inputs=[inverse])
    normal = t.node_output("ShaderNodeVectorMath", "Vector", operation="NORMALIZE", inputs=[t.world(summed, normals)])
    captured, (position, normal) = t.capture(
        geometry, [("VECTOR", "Start Position", t.position()), ("VECTOR", "Start Normal", normal)]
    )
    return t.switch("GEOMETRY", on, geometry, captured), position, normal


def _deviation_map(t, geometry, on, start_position, start_normal, transform):
    """``geometry`` with, where ``on``, the point attribute hc_deviation: the world-space move (position - start
    through ``transform``) along the world-space start normal. Where the mesh already has an attribute of that
    name (the user's of any type or domain, a UV map or a vertex group, or an earlier map) nothing is stored
    and the Warnings panel says why: what the user made is never overwritten."""
    named = t.node("GeometryNodeInputNamedAttribute", data_type="FLOAT")
    named.inputs["Name"].default_value = DEVIATION_ATTRIBUTE
    taken = t.math("GREATER_THAN", t.statistic(geometry, named.outputs["Exists"], "Max"), 0.5)
    kept = t.warning(t.boolean("AND", on, taken), NAME_TAKEN, "WARNING")
    moved = t.world(t.subtract(t.position(), start_position), transform)
    deviation = t.node_output("ShaderNodeVectorMath", "Value", operation="DOT_PRODUCT", inputs=[moved, start_normal])
    store = t.node("GeometryNodeStoreNamedAttribute", data_type="FLOAT", domain="POINT")
    t.feed(store.inputs["Geometry"], geometry)
    store.inputs["Name"].default_value = DEVIATION_ATTRIBUTE
    t.feed(store.inputs["Value"], deviation)
    return t.switch("GEOMETRY", t.boolean("AND", on, t.boolean("NOT", kept)), geometry, store.outputs["Geometry"])


def _checked_inputs(t, value, is_hc):
    """(alpha, beta, iterations, limit, refused): the single-value inputs clamped to their ranges, and whether
    the mesh must pass through unchanged (a NaN input; HC where it can blow up). Each case is a line in the
    Warnings panel: a clamp is an Info, a refusal an Error."""
    refusals = []

    def checked(setting, low, high, clamped):
        raw, name = value(setting), input_name(setting)
        if setting.kind == "float":
            not_a_number = t.boolean("NOT", t.is_number(raw))
            refusals.append(t.warning(not_a_number, f"{name} is not a number: {PASSED_THROUGH}"))
        t.warning(t.outside(raw, low, high), f"{name} {clamped}", "INFO")
        return t.clamp(raw, low, high)

    alpha = checked(settings_spec.ALPHA, 0.0, 1.0, "is outside 0 to 1: the nearest of the two is used")
    beta = checked(settings_spec.BETA, 0.0, 1.0, "is outside 0 to 1: the nearest of the two is used")
    most = settings_spec.MODIFIER_MAX_ITERATIONS
    iterations = checked(
        settings_spec.MODIFIER_ITERATIONS,
        0.0,
        float(most),
        f"is outside 0 to {most} (Blender cannot interrupt a modifier while it evaluates): the nearest is used",
    )
    limit = checked(settings_spec.MODIFIER_MAX_DEVIATION, 0.0, None, "is below 0: no limit")

    runs_hc = t.boolean("AND", is_hc, t.math("GREATER_THAN", iterations, 0.5))
    unbounded = t.boolean(
        "AND", t.math("LESS_THAN", beta, 0.5), t.math("GREATER_THAN", iterations, SAFE_HC_STEPS + 0.5)
    )
    unbounded = t.warning(
        t.boolean("AND", is_hc, unbounded),
        f"HC with Beta below 0.5 can blow up: it runs at most {SAFE_HC_STEPS} iterations; raise Beta to 0.5 or "
        f"more (paper, Theorem 5.2): {PASSED_THROUGH}",
    )
    refusals.append(unbounded)
    proven = t.boolean("AND", t.math("GREATER_THAN", alpha, 0.0), t.math("GREATER_THAN", beta, 0.5))
    t.warning(
        t.boolean("AND", t.boolean("AND", runs_hc, t.boolean("NOT", proven)), t.boolean("NOT", unbounded)),
        "HC is proven to converge only for Alpha > 0 and Beta > 0.5 (paper, Theorem 5.2): many iterations may "
        "drift or shrink the mesh",
        "INFO",
    )
    return alpha, beta, iterations, limit, t.any_of(refusals)


def _guarded(t, geometry, smoothed, refused):
    """``smoothed``, or ``geometry`` unchanged where the inputs are refused or the result has blown up (a
    coordinate not finite, or core's test: a bounding box around input and result BLOW_UP_FACTOR times the
    input's diagonal)."""
    result = t.switch("GEOMETRY", refused, smoothed, geometry)  # refused: the smoothing is not evaluated
    box_in, box_out = t.node("GeometryNodeBoundBox"), t.node("GeometryNodeBoundBox")
    t.feed(box_in.inputs[0], geometry)
    t.feed(box_out.inputs[0], result)
    low = t.vector("MINIMUM", box_in.outputs["Min"], box_out.outputs["Min"])
    high = t.vector("MAXIMUM", box_in.outputs["Max"], box_out.outputs["Max"])
    size = t.diagonal(box_in.outputs["Min"], box_in.outputs["Max"])
    grown = t.math("GREATER_THAN", t.diagonal(low, high), t.math("MULTIPLY", size, BLOW_UP_FACTOR))
    # Bounding Box skips NaN: each point's sum of |coordinates|, compared so that NaN and inf fail.
    magnitude = t.node_output(
        "ShaderNodeVectorMath",
        "Value",
        operation="DOT_PRODUCT",
        inputs=[
            t.node_output("ShaderNodeVectorMath", "Vector", operation="ABSOLUTE", inputs=[t.position()]),
            (1, 1, 1),
        ],
    )
    infinite = t.math("SUBTRACT", 1.0, t.math("LESS_THAN", magnitude, LARGEST_FINITE))
    infinite = t.math("GREATER_THAN", t.statistic(result, infinite, "Max"), 0.0)
    blown = t.boolean("AND", t.boolean("NOT", refused), t.boolean("OR", grown, infinite))
    blown = t.warning(
        blown,
        f"Smoothing blew up (a coordinate not finite, or the bounding box more than {BLOW_UP_FACTOR:g} times the "
        f"input's): {PASSED_THROUGH}",
    )
    return t.switch("GEOMETRY", blown, result, geometry)


# --- one group per file, rebuilt when the add-on's is newer -------------------------------------------------


def find_group():
    """The file's HC Smooth group (found by its version marker, not its name), or None."""
    groups = [group for group in bpy.data.node_groups if group.bl_idname == "GeometryNodeTree" and VERSION_KEY in group]
    if not groups:
        return None
    # Local before linked (a linked one cannot be rebuilt), the newest version, then the plain name.
    return min(
        groups,
        key=lambda group: (group.library is not None, -int(group[VERSION_KEY]), group.name != GROUP_NAME, group.name),
    )


def ensure_group():
    """The group the modifier uses: built once per file and reused; a group of an older version of the add-on
    is rebuilt in place, keeping every modifier's settings. A newer or linked one is used as it is."""
    group = find_group()
    if group is None:
        group = bpy.data.node_groups.new(GROUP_NAME, "GeometryNodeTree")
        _fill(group)
    elif int(group[VERSION_KEY]) < VERSION and group.library is None:
        rebuild(group)
    return group


def _fill(group):
    build(group)
    group[VERSION_KEY] = VERSION
    group.is_modifier = True  # offered in the Geometry Nodes modifier's group selector
    if hasattr(group, "description"):  # the tooltip in the Add Modifier menu (4.x and later)
        group.description = (
            "Smooth away scan noise without shrinking (HC, Vollmer, Mencl, M\u00fcller 1999); simultaneous mode"
        )


def rebuild(group):
    """Replace the nodes and interface of ``group`` by this version's, keeping every modifier's input values
    (by input name; inputs this version's interface lacks are dropped)."""
    from . import inputs

    users = [
        modifier
        for obj in bpy.data.objects
        for modifier in obj.modifiers
        if modifier.type == "NODES" and modifier.node_group == group
    ]
    saved = []
    for modifier in users:
        values = {}
        for item in group.interface.items_tree:
            if item.item_type == "SOCKET" and item.in_out == "INPUT" and item.socket_type != "NodeSocketGeometry":
                try:
                    values[item.name] = (
                        inputs.get_input(modifier, item.name),
                        inputs.get_input_attribute(modifier, item.name),
                    )
                except (KeyError, AttributeError, TypeError):
                    continue
        saved.append((modifier, values))
    group.nodes.clear()
    group.interface.clear()
    _fill(group)
    for modifier, values in saved:
        modifier.node_group = group  # makes the modifier's inputs match the new interface
        for name, (value, attribute) in values.items():
            try:
                inputs.set_input(modifier, name, value)
                if attribute:
                    inputs.set_input_attribute(modifier, name, attribute)
            except (KeyError, AttributeError, TypeError, ValueError):  # absent here, or of another type
                continue
