"""Every setting of HC Smooth, declared once: identifier, kind, label, description, default, limits,
enum items, how panels draw it, and for the command line its option and help.

Built from it: the operators' properties and the scene settings (operators/properties.py), the rows of
every panel (operators/draw.py: the operators' redo panels and the N-panel), the presets' list (ui/settings.py),
the command-line options (cli/arguments.py), the modifier's inputs (nodes/hc_group.py), and the plain
settings objects (MeshSettings, PointSettings) that the operators snapshot and the command line fills. A
top-level module, not one inside operators/, ui/ or cli/: those packages import bpy in their
``__init__``, and this must import without Blender, so that the command line is parsed before Blender
loads anything and tests/core can check it on its own. Plain Python only, and no imports from the rest
of the package.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass, field, fields, make_dataclass, replace

KINDS = {"enum": str, "float": float, "int": int, "bool": bool, "string": str}


@dataclass(frozen=True)
class Choice:
    """One item of an enum setting."""

    identifier: str
    label: str
    description: str
    short: str = ""  # the name in reports and shape keys, where the label is too long
    core: str = ""  # the name core uses for it


@dataclass(frozen=True)
class Setting:
    """One setting. Limits left at None are Blender's defaults (and no limit on the command line)."""

    name: str  # the property identifier: operators, scene settings, presets and users' scripts use it
    kind: str  # a key of KINDS
    label: str
    description: str  # a sentence without a final period, as Blender's tooltips
    default: object
    items: tuple = ()  # Choice, for enums
    min: float = None
    max: float = None
    soft_max: float = None
    step: float = None  # UI drag step in hundredths, as bpy.props takes it
    precision: int = None
    subtype: str = None  # Blender's property subtype, e.g. "DISTANCE" (shown in scene units)
    flag: str = None  # the command-line option without "--"; None: not on the command line
    metavar: str = None
    help: str = None  # the command-line help, lower case; the parser adds the default
    cli_default: str = None  # how --help states the default, when not just the value ({default}: the value)
    points_keep: object = None  # a mesh-only option: the value --points accepts (what point clouds run anyway)
    argument: str = None  # the core.MeshSmoother argument it sets (enums: each Choice's ``core`` name)
    chosen: bool = False  # with the Automatic Amount on, chosen by core unless the caller sets it
    # How panels draw it (operators/draw.py). The rules read the values of the settings drawn with it: {name: value}.
    # active(values, given=()): False: greyed out, still editable (it applies once the rule holds). ``given``:
    # the names the caller set, as ``automatic`` reads them (an operator's redo panel has them).
    active: Callable = None
    text: Callable = None  # the label drawn, where it depends on other settings
    invert: str = None  # a vertex group's name: the bool setting that inverts it, drawn beside it as a toggle

    @property
    def identifiers(self):
        return tuple(choice.identifier for choice in self.items)


def settings_class(name, settings, doc):
    """A dataclass with one field per setting, defaults as declared: the plain stand-in for an operator's
    properties that the command line hands to the job code. ``of(props)`` snapshots an operator's."""

    def of(cls, props):
        """A snapshot of an operator's properties (a modal run must not see later edits)."""
        return cls(**{f.name: getattr(props, f.name) for f in fields(cls)})

    return make_dataclass(
        name,
        [(s.name, KINDS[s.kind], field(default=s.default)) for s in settings],
        namespace={"of": classmethod(of), "__doc__": doc},
    )


# --- meshes: object.hc_smooth, mesh.hc_smooth and the scene settings (scene.hc_smooth) -----------------


def automatic(values, given=()):
    """Whether the Automatic Amount chooses the amount: the one rule the panels' greying, the buttons, the
    operators and the command line read.

    ``values``: {name: value} of the mesh or point-cloud settings (``values_of``); for meshes at least method,
    keep_sharp_edges and auto_amount. Settings without auto_amount (the modifier's) have no Automatic Amount.
    ``given``: the names the caller set (Blender's ``is_property_set``, a command line's options): one of
    SWITCHES_OFF_THE_AMOUNT among them runs every number as set. Meshes: it runs for HC, and for Keep Sharp
    Edges (its own) whatever the method; point clouds run HC."""
    if "auto_amount" not in values or not values["auto_amount"] or set(SWITCHES_OFF_THE_AMOUNT) & set(given):
        return False
    return ITERATIONS_PER_ROUND.name in values or values["method"] == "HC" or bool(values["keep_sharp_edges"])


def chosen(values, given=()):
    """The names of the mesh settings the Automatic Amount chooses in a run: those of CHOSEN not given, or
    none where it does not run (then every number runs as set)."""
    return frozenset(CHOSEN) - set(given) if automatic(values, given) else frozenset()


def passed_by_panel(values, changed):
    """The names of the mesh settings a panel's button hands to the operator, which takes them as given:
    all but those the Automatic Amount chooses and the user left alone. ``changed``: the names the user
    changed in the panel; Alpha and Iterations among them do not count, since the panel greys them out
    while the Automatic Amount runs (its checkbox switches it off), so a button never passes what its panel
    shows greyed out."""
    left = chosen(values, set(changed) - set(SWITCHES_OFF_THE_AMOUNT))
    return tuple(setting.name for setting in MESH if setting.name not in left)


def keeps_in_place(values, given=()):
    """Whether Keep in Place applies: HC's Automatic Amount runs (not Keep Sharp Edges', not set numbers).
    The checkbox then decides; where it does not apply the paper's moves run."""
    return automatic(values, given) and not values["keep_sharp_edges"]


def values_of(props, settings):
    """{name: value} of ``settings`` on ``props`` (an operator's properties, the scene settings, a snapshot):
    what the declared rules (``automatic``, each setting's ``active`` and ``text``) read."""
    return {setting.name: getattr(props, setting.name) for setting in settings}


METHOD = Setting(
    "method",
    "enum",
    "Method",
    "Smoothing algorithm",
    "HC",
    items=(
        Choice(
            "HC",
            "HC",
            "Laplacian step, then push every vertex back towards its previous and original "
            "position: removes noise without shrinking (Vollmer, Mencl, M\u00fcller 1999)",
            short="HC",
            core="hc",
        ),
        Choice(
            "LAPLACIAN",
            "Laplacian",
            "Move every vertex to the average of its neighbours: shrinks with every iteration (paper 3.1)",
            short="Laplacian",
            core="plain",
        ),
        Choice(
            "LAPLACIAN_CENTRAL",
            "Laplacian, Central Point",
            "Laplacian that keeps Alpha of the current position: slower, shrinks the same way (paper 3.2)",
            short="Laplacian (central)",
            core="central",
        ),
        Choice(
            "LAPLACIAN_ORIGINAL",
            "Laplacian, Original Point",
            "Laplacian that pulls towards the original "
            "position with weight Alpha: converges, but shrinks part of the way (paper 3.3)",
            short="Laplacian (original)",
            core="original",
        ),
    ),
    flag="method",
    help="smoothing algorithm",
    argument="method",
    points_keep="HC",
    active=lambda values, given=(): not values.get("keep_sharp_edges", False),  # Keep Sharp Edges smooths its own way
)
KEEP_SHARP_EDGES = Setting(
    "keep_sharp_edges",
    "bool",
    "Keep Sharp Edges",
    "For hard-surface scans (machined, cast, CAD parts): smooth the face normals without averaging across "
    "edges sharper than Sharpness, then fit the vertices to them with HC's push-back (Sun et al. 2007, with "
    "Zhang et al. 2015's guided filtering). Replaces the method; Iterations count its steps. Slower than HC, "
    "and worse on organic shapes",
    False,
    flag="keep-sharp-edges",
    help="keep sharp edges (hard-surface scans): normals are not averaged across edges sharper than "
    "--sharpness-angle; replaces --method",
    argument="keep_sharp_edges",
)
SHARPNESS_ANGLE = Setting(
    "sharpness_angle",
    "float",
    "Sharpness",
    "Keep Sharp Edges: faces meeting at more than this angle stay apart, as Blender's Auto Smooth angle. "
    "The Automatic Amount may widen it to the angle the noise alone tilts faces by",
    math.radians(30.0),
    min=math.radians(1.0),
    max=math.radians(179.0),
    step=100,
    precision=1,
    subtype="ANGLE",
    flag="sharpness-angle",
    metavar="DEGREES",
    help="with --keep-sharp-edges: faces meeting at more than this angle, in degrees, stay apart",
    argument="sharpness_angle",
    active=lambda values, given=(): values.get("keep_sharp_edges", False),
)
MESH_AUTO_AMOUNT = Setting(
    "auto_amount",
    "bool",
    "Automatic Amount",
    "HC: choose Iterations (with Alpha 0) from the noise the mesh itself shows, by cross-validating what the "
    "iterations remove, and give closed parts back the volume they had. Off: use Alpha and Iterations as set",
    True,
    active=lambda values, given=(): values["method"] == "HC" or values.get("keep_sharp_edges", False),
)
KEEP_IN_PLACE = Setting(
    "keep_in_place",
    "bool",
    "Keep in Place",
    "With Automatic Amount: every vertex moves only across the surface, along its normal, never along it: "
    "textures, UVs and open outlines stay where they were. Off: vertices also slide along the surface as the "
    "paper's HC moves them (Keep Sharp Edges and set numbers always do)",
    True,
    flag="slide",
    help="let vertices slide along the surface as the paper's HC moves them (textures, UVs and outlines move "
    "with them); by default the Automatic Amount moves every vertex only across the surface",
    argument="keep_in_place",
    active=lambda values, given=(): keeps_in_place(values, given),
)
ALPHA = Setting(
    "alpha",
    "float",
    "Alpha",
    "HC and Laplacian with original point: weight of the original position (0 = none, higher keeps more "
    "of the input, noise included). Laplacian with central point: weight of the current position. HC with "
    "Automatic Amount: chosen (0) unless set; setting Alpha or Iterations runs both as set",
    0.1,
    min=0.0,
    max=1.0,
    step=1,
    precision=3,
    flag="alpha",
    help="pull towards the original",
    cli_default="{default}; HC: chosen with the iterations unless --alpha or --iterations is given",
    # Plain Laplacian has no alpha; with the Automatic Amount, alpha applies once it is off.
    active=lambda values, given=(): (
        (values["method"] != "LAPLACIAN" or values.get("keep_sharp_edges", False)) and not automatic(values, given)
    ),
    text=lambda values: (
        "Alpha (keep current)" if values["method"] == "LAPLACIAN_CENTRAL" else "Alpha (pull to original)"
    ),
    argument="alpha",
    chosen=True,
)
BETA = Setting(
    "beta",
    "float",
    "Beta",
    "HC: weight of a vertex's own correction against its neighbours'. Convergence is proven for "
    "Beta > 0.5 (with Alpha > 0)",
    0.6,
    min=0.0,
    max=1.0,
    step=1,
    precision=3,
    flag="beta",
    help="HC correction weight",
    active=lambda values, given=(): values["method"] == "HC" or values.get("keep_sharp_edges", False),
    argument="beta",
    chosen=True,
)
ITERATIONS = Setting(
    "iterations",
    "int",
    "Iterations",
    "Number of smoothing iterations (heavier noise needs more). HC with Automatic Amount: chosen from the "
    "noise unless set; setting Alpha or Iterations runs both as set",
    10,
    min=0,
    soft_max=200,
    flag="iterations",
    help="smoothing iterations",
    cli_default="{default}; HC: chosen from the noise unless --alpha or --iterations is given",
    active=lambda values, given=(): not automatic(values, given),
    argument="iterations",
    chosen=True,
)
MODE = Setting(
    "mode",
    "enum",
    "Mode",
    "Order in which vertices are updated within an iteration",
    "SIMULTANEOUS",
    items=(
        Choice(
            "SIMULTANEOUS",
            "Simultaneous",
            "Every vertex reads the positions of the previous iteration (paper, Algorithm 1)",
            core="simultaneous",
        ),
        Choice(
            "SEQUENTIAL",
            "Sequential",
            "Vertices in index order, each reading the already updated "
            "positions of lower-index neighbours (Gauss\u2013Seidel)",
            core="sequential",
        ),
    ),
    flag="mode",
    help="order of the updates within an iteration",
    argument="mode",
    points_keep="SIMULTANEOUS",
)
TOLERANCE = Setting(
    "tolerance",
    "float",
    "Tolerance",
    "Stop early once no vertex moves more than this fraction of the bounding-box diagonal in an "
    "iteration (0 = always run every iteration)",
    0.0,
    min=0.0,
    soft_max=0.01,
    step=0.01,
    precision=6,
    flag="tolerance",
    help="stop early below this move, a fraction of the bounding-box diagonal",
    argument="tolerance",
    points_keep=0.0,
)
VERTEX_GROUP = Setting(
    "vertex_group",
    "string",
    "Fixed Group",
    "Vertices in this group (weight above 0) stay fixed (empty: none)",
    "",
    flag="fixed-group",
    metavar="NAME",
    help="vertices (points) in this vertex group stay fixed (.blend, OBJ groups)",
    invert="invert_vertex_group",
)
INVERT_VERTEX_GROUP = Setting(
    "invert_vertex_group",
    "bool",
    "Invert Fixed Group",
    "Fix every vertex outside the group instead: smooth only the group",
    False,
    flag="invert-group",
    help="fix everything outside --fixed-group instead (smooth only the group)",
)
PIN_BOUNDARY = Setting(
    "pin_boundary",
    "bool",
    "Pin Boundary",
    "Keep the vertices on open boundaries (holes, borders) fixed",
    False,
    flag="pin-boundary",
    help="keep open-boundary vertices fixed",
)
KEEP_OUTLINE = Setting(
    "keep_outline",
    "bool",
    "Keep Outline",
    "Smooth open boundaries along themselves, as curves, instead of pulling them into the surface: a "
    "range scan's outline stays in place (corners where boundaries meet stay fixed). Holes of a few "
    "boundary vertices shrink, and a little more noise stays next to ragged outlines",
    False,
    flag="keep-outline",
    help="smooth open boundaries as curves instead of pulling them in (--pin-boundary wins)",
    active=lambda values, given=(): not values["pin_boundary"],
)
INFLUENCE_GROUP = Setting(
    "influence_group",
    "string",
    "Influence",
    "Vertex group whose weights scale how far each vertex moves in every iteration (0 = stays, 1 = the full "
    "step; empty: full everywhere), for smoothing painted where the scan is noisy",
    "",
    flag="influence-group",
    metavar="NAME",
    help="vertex group whose weights scale each vertex's move (0 stays, 1 full; .blend, OBJ groups)",
    invert="invert_influence_group",
)
INVERT_INFLUENCE_GROUP = Setting(
    "invert_influence_group",
    "bool",
    "Invert Influence",
    "Use one minus the weights of the influence group",
    False,
    flag="invert-influence",
    help="use one minus the --influence-group weights",
)
OUTPUT = Setting(
    "output",
    "enum",
    "Output",
    "Where the result goes",
    "MESH",
    items=(
        Choice("MESH", "Mesh", "Move the vertices (of the active shape key, if the mesh has shape keys)"),
        Choice("SHAPE_KEY", "New Shape Key", "Write the result into a new shape key and leave the mesh as it was"),
    ),
)
DEVIATION_MAP = Setting(
    "deviation_map",
    "bool",
    "Deviation Map",
    "Store each vertex's signed move along its normal as the point attribute hc_deviation, with a colour "
    "attribute (blue inwards, red outwards) shown in the viewport's Solid shading; the report gives the range",
    False,
    flag="deviation-attribute",
    help="store each vertex's signed move along its normal as the vertex attribute hc_deviation "
    "(PLY: a float vertex property; .blend: a mesh attribute with a colour attribute; OBJ and STL cannot hold it)",
)

# The mesh settings in three parts, each drawn together. How strongly to smooth: the N-panel's main
# settings, and what a preset stores.
MAX_DEVIATION = Setting(
    "max_deviation",
    "float",
    "Deviation Limit",
    "The farthest any vertex may end from where it started, in world space (on the object as scaled), kept "
    "inside every iteration (0 = no limit). HC with Automatic Amount: a multiple of the noise it finds, unless set",
    0.0,
    min=0.0,
    soft_max=1.0,
    step=0.1,
    precision=4,
    subtype="DISTANCE",
    flag="max-deviation",
    metavar="D",
    help="the farthest any vertex may move, in scene units (0: no limit)",
    cli_default="{default}; HC: a multiple of the noise unless --alpha or --iterations is given",
    argument="max_deviation",
    chosen=True,
)

MESH_SMOOTHING = (
    METHOD,
    KEEP_SHARP_EDGES,
    SHARPNESS_ANGLE,
    MESH_AUTO_AMOUNT,
    KEEP_IN_PLACE,
    ALPHA,
    BETA,
    ITERATIONS,
    MODE,
    TOLERANCE,
    MAX_DEVIATION,
)
# Which vertices move, and how far (the N-panel's Fixed Vertices): they belong to one mesh, so presets leave them.
MESH_VERTICES = (
    VERTEX_GROUP,
    INVERT_VERTEX_GROUP,
    PIN_BOUNDARY,
    KEEP_OUTLINE,
    INFLUENCE_GROUP,
    INVERT_INFLUENCE_GROUP,
)
MESH_RESULT = (OUTPUT, DEVIATION_MAP)
MESH = MESH_SMOOTHING + MESH_VERTICES + MESH_RESULT
# What the Automatic Amount chooses unless the caller sets it (SWITCHES_OFF_THE_AMOUNT, below, given: none).
CHOSEN = tuple(setting.name for setting in MESH if setting.chosen)

# --- point clouds: object.hc_smooth_points --------------------------------------------------------------

AUTO_AMOUNT = Setting(
    "auto_amount",
    "bool",
    "Automatic Amount",
    "Choose Steps per Round and Alpha from the noise estimated relative to the point spacing (noisier: "
    "more steps and a weaker pull; nearly clean, sparse points: a few steps). Off: use the values set below",
    True,
)
POINT_ALPHA = replace(
    ALPHA,
    default=0.01,
    step=0.1,
    description="Pull towards the original positions (small: more smoothing; raise it for nearly clean, "
    "sparse points). Used when Automatic Amount is off",
    cli_default="chosen from the noise unless given, then --steps-per-round applies",
    active=lambda values, given=(): not automatic(values, given),
    text=None,
)
POINT_BETA = replace(
    BETA,
    default=0.55,
    description="Weight of a point's own correction against its neighbours'. Convergence is proven for "
    "Beta > 0.5 (with Alpha > 0)",
    active=None,  # points run HC only: Beta always applies
)
ROUNDS = Setting(
    "rounds",
    "int",
    "Rounds",
    "Runs of Steps per Round HC steps, with edge swapping of the RFS mesh in between (with Automatic Amount "
    "the chosen steps are spread over the rounds)",
    3,
    min=0,
    soft_max=50,
    flag="rounds",
    help="runs of HC steps with edge swapping between them",
)
ITERATIONS_PER_ROUND = Setting(
    "iterations_per_round",
    "int",
    "Steps per Round",
    "HC iterations between two passes of edge swapping. Used when Automatic Amount is off",
    22,
    min=1,
    soft_max=100,
    flag="steps-per-round",
    metavar="N",
    help="HC steps per round",
    cli_default="chosen from the noise unless given, then {default} and --alpha apply",
    active=lambda values, given=(): not automatic(values, given),
)
NEIGHBOURS = Setting(
    "neighbours",
    "int",
    "Neighbours",
    "How many nearest neighbours each point may connect to",
    16,
    min=2,
    soft_max=64,
    flag="neighbours",
    metavar="N",
    help="nearest neighbours a point may connect to",
)
SPACING_FACTOR = Setting(
    "spacing_factor",
    "float",
    "Reach",
    "Connect neighbours up to this many times the local point spacing (larger: wider neighbourhoods, "
    "stronger smoothing)",
    2.5,
    min=0.1,
    soft_max=5.0,
    flag="reach",
    metavar="R",
    help="connect neighbours up to R local spacings",
)
GAP_FACTOR = Setting(
    "gap_factor",
    "float",
    "Gap",
    "Never connect across a gap wider than this many local spacings: separate parts stay separate (must be "
    "at least Reach)",
    3.0,
    min=0.1,
    soft_max=10.0,
    flag="gap",
    metavar="G",
    help="never connect across a gap of G local spacings, at least --reach",
)
MIN_QUALITY = Setting(
    "min_quality",
    "float",
    "Face Quality",
    "Drop RFS faces below this Bank-Smith quality (1 = equilateral)",
    0.3,
    min=0.0,
    max=1.0,
)
SWAP = Setting(
    "swap",
    "bool",
    "Edge Swapping",
    "Swap edges of the RFS mesh between HC steps (paper section 7)",
    True,
)
POINT_VERTEX_GROUP = replace(
    VERTEX_GROUP,
    description="Points in this vertex group (weight above 0) stay fixed; for point cloud objects, a point "
    "attribute of that name",
)
POINT_INVERT_VERTEX_GROUP = replace(INVERT_VERTEX_GROUP, description="Fix every point outside the group instead")
KEEP_RFS_MESH = Setting(
    "keep_rfs_mesh",
    "bool",
    "Keep RFS Mesh",
    "Add the final RFS mesh as a new wireframe object to inspect it",
    False,
)

# Either of these given switches the Automatic Amount off (then every number runs as set): meshes' Alpha and
# Iterations, point clouds' Alpha and Steps per Round.
SWITCHES_OFF_THE_AMOUNT = (ALPHA.name, ITERATIONS.name, ITERATIONS_PER_ROUND.name)

POINTS = (
    AUTO_AMOUNT,
    POINT_ALPHA,
    POINT_BETA,
    ROUNDS,
    ITERATIONS_PER_ROUND,
    NEIGHBOURS,
    SPACING_FACTOR,
    GAP_FACTOR,
    MIN_QUALITY,
    SWAP,
    POINT_VERTEX_GROUP,
    POINT_INVERT_VERTEX_GROUP,
    KEEP_RFS_MESH,
)

# --- the HC Smooth modifier: object.hc_smooth_modifier_add and the modifier's node group ------------------
# The mesh settings a modifier can hold: it runs simultaneous mode and every iteration (no Mode, no
# Tolerance), on the evaluated mesh (no Output). Each is an input of the node group named by the setting's
# label: saved files and users' scripts set the inputs by these names. Iterations and Deviation Limit are the
# mesh settings of those names with the modifier's own limits and tooltips.

# A Geometry Nodes evaluation cannot be cancelled: the modifier's Iterations has a hard maximum besides the
# panels' soft one, chosen from the seconds per 1000 HC iterations that bench/bench_modifier_limits.py measures
# (docs/modifier.md, "Limits").
MODIFIER_MAX_ITERATIONS = 1000
# The command line runs unattended (batches, farms): its Iterations has the modifier's hard maximum too, and so
# have a point cloud's HC steps (Rounds times Steps per Round, at least one step a round), so that a mistyped
# count cannot keep it going without end (a long operator run can be cancelled with Esc).
COMMAND_MAX_ITERATIONS = MODIFIER_MAX_ITERATIONS
MODIFIER_ITERATIONS = replace(
    ITERATIONS,
    description="Number of smoothing iterations (heavier noise needs more). At most "
    f"{MODIFIER_MAX_ITERATIONS}: Blender cannot interrupt a modifier while it evaluates, and {MODIFIER_MAX_ITERATIONS} "
    "HC iterations take 15-20 s on 100k vertices",
    max=MODIFIER_MAX_ITERATIONS,
    flag=None,
    cli_default=None,
)
MODIFIER_MAX_DEVIATION = replace(
    MAX_DEVIATION,
    description="The farthest any vertex may end from where it started, in world space (on the object as scaled), "
    "kept inside every iteration (0 = no limit)",
    flag=None,
    cli_default=None,
)
MODIFIER_DEVIATION_MAP = replace(
    DEVIATION_MAP,
    description="Store each vertex's signed move along its input normal as the point attribute hc_deviation "
    "(for the Spreadsheet, or a material's Attribute node)",
    flag=None,
    help=None,
)

MODIFIER = (
    METHOD,
    ALPHA,
    BETA,
    MODIFIER_ITERATIONS,
    MODIFIER_MAX_DEVIATION,
    VERTEX_GROUP,
    INVERT_VERTEX_GROUP,
    PIN_BOUNDARY,
    INFLUENCE_GROUP,
    INVERT_INFLUENCE_GROUP,
    MODIFIER_DEVIATION_MAP,
)

# --- plain settings objects: an operator's snapshot, or what the command line fills ---------------------------

MeshSettings = settings_class(
    "MeshSettings",
    MESH,
    "The mesh settings as plain values: a mesh operator's snapshot (a modal run must not see later edits).",
)
PointSettings = settings_class(
    "PointSettings",
    POINTS,
    "The point-cloud settings: the operator's properties (their defaults are these) or the command line's.",
)
