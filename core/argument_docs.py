"""The smoothers' shared arguments, described once: ``documented`` puts each entry where a docstring
says {name}, so hc_smooth, laplacian_smooth, smooth and Smoothing describe them alike."""

import inspect

# The shared arguments, described once: documented puts each entry where a docstring says {name}.
DOCS = {
    "arrays": """\
positions : (n, 3) array_like of float32 or float64
    Vertex positions; never modified. The result has the same shape and dtype.
edges : (m, 2) array_like of int, or None
    Vertex pairs, undirected: order, direction and duplicates do not matter, self-loops are
    ignored. adj(i) is the set of vertices sharing an edge with i. Not read when ``operator`` is
    given (pass None).""",
    "numbers": """\
method : {"hc", "plain", "central", "original"}, default "hc"
    HC (paper section 4, Algorithm 1) or a Laplacian variant: plain (3.1), with the central
    point (3.2), with the original point (3.3). See `METHODS`.
alpha : float in [0, 1], default 0.1 (DEFAULT_ALPHA)
    Weight of the original point o_i (``"hc"``, ``"original"``) or of the current point q_i
    (``"central"``); ``"plain"`` does not use it.
beta : float in [0, 1], default 0.6 (DEFAULT_BETA)
    HC's weight of a vertex's own difference b_i against its neighbours' mean difference
    (``"hc"`` only).
iterations : int >= 0
    How many iterations to run (fewer when ``tolerance`` stops the run).""",
    "options": """\
mode : {"simultaneous", "sequential"}, default "simultaneous"
    ``"simultaneous"`` is the paper's Algorithm 1 (Jacobi). ``"sequential"`` is Gauss–Seidel:
    vertices in increasing index order, each average using the already-updated positions of its
    lower-index neighbours (for HC the Laplacian pass; the correction uses the b of the whole pass).
fixed : (n,) bool mask or array_like of vertex indices, optional
    Vertices that never move (bit-identical). Vertices without neighbours are fixed too (paper
    section 2).
tolerance : float >= 0, default 0.0
    Stop once the largest move of an iteration is below ``tolerance`` times the bounding-box
    diagonal of ``positions`` (0: always run ``iterations``).
original : (n, 3) array_like, optional
    The paper's original points o when they differ from ``positions`` (a run that goes on from
    another one's result); default ``positions``.
operator : Umbrella, optional
    A prebuilt ``umbrella_operator(edges, n)``, reused across runs; ``edges`` is then not read.
influence : (n,) array_like of float in [0, 1], optional
    Per-vertex share of each iteration's move (a painted vertex group): vertex i ends an
    iteration at q_i + w_i (p_i - q_i). 0 stays bit-identical; 1 (or None) is the paper's step.
max_deviation : float >= 0, or (n,) ndarray of them, default 0.0
    The deviation limit: the farthest any vertex may end an iteration from its input position, in
    the positions' units (every iteration ends with a projection onto that ball); 0: no limit, the
    paper's algorithm. An array gives each vertex its own distance (0 keeps that vertex in place).""",
    "progress": """\
progress : callable, optional
    ``progress(done, total)`` is called after each iteration; returning False stops the run and
    raises `Cancelled`.""",
    "wrapper": """\
Other Parameters
----------------
{options}
{progress}

Returns
-------
ndarray
    The new positions, same shape and dtype as ``positions``.

Raises
------
{raises}
Cancelled
    ``progress`` returned False.""",
    "raises": """\
ValueError
    Bad input, with a message saying what to fix: wrong shapes, NaN or infinite coordinates,
    indices out of range, alpha or beta outside [0, 1], negative iterations, an unknown method or
    mode.
DivergenceError
    The run blew up (only possible outside the convergence region); nothing is returned.""",
}


def documented(thing):
    """``thing`` with each {name} of its docstring replaced by the entries DOCS[name]."""
    if thing.__doc__:  # None under python -OO
        text = inspect.cleandoc(thing.__doc__)  # Python 3.13 dedents docstrings itself, 3.11 does not
        for _ in range(2):  # an entry may hold others ("wrapper")
            for name, entries in DOCS.items():
                text = text.replace("{" + name + "}", entries)
        thing.__doc__ = text
    return thing
