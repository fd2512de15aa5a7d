"""Convergence of the smoothers (paper section 5): the proven region, and what users are told about it (a
sentence for reports, short lines for panels)."""


class ConvergenceWarning(UserWarning):
    """HC was asked to run with (alpha, beta) outside the region where Theorem 5.2 proves convergence.

    The run goes on: few iterations outside the region are often harmless, and alpha = 0 is what the
    Automatic Amount runs on purpose.

    Examples
    --------
    >>> import warnings, numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     _ = core.hc_smooth(positions, edges, alpha=0.0, beta=0.6, iterations=3)
    >>> [warning.category.__name__ for warning in caught]
    ['ConvergenceWarning']
    """


class DivergenceError(ValueError):
    """A run blew up (non-finite coordinates, or a bounding box many times the input's).

    Nothing is returned, so no caller can write the garbage; the input is untouched. Only possible
    outside the convergence region. A ValueError: the arguments were unusable.

    Examples
    --------
    A square is bipartite: HC with alpha = beta = 0 makes its corners swing further every step.

    >>> import warnings, numpy as np, core
    >>> square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.1]])
    >>> edges = [[0, 1], [1, 2], [2, 3], [3, 0]]
    >>> with warnings.catch_warnings(action="ignore"):
    ...     core.hc_smooth(square, edges, alpha=0.0, beta=0.0, iterations=20)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    core.convergence.DivergenceError: HC with alpha 0 and beta 0 blew up after 20 iterations ...
    """


def in_convergence_region(alpha, beta):
    """Whether HC is proven to converge with these weights: alpha > 0 and beta > 0.5 (Theorem 5.2).

    Parameters
    ----------
    alpha, beta : float
        HC's weights (see ``core.hc_smooth``).

    Returns
    -------
    bool

    Examples
    --------
    >>> import core
    >>> core.in_convergence_region(0.1, 0.6), core.in_convergence_region(0.0, 0.6)
    (True, False)
    """
    return alpha > 0.0 and beta > 0.5


def convergence_message(alpha, beta):
    """A sentence for users about where (alpha, beta) lies outside the proven region.

    Parameters
    ----------
    alpha, beta : float
        HC's weights (see ``core.hc_smooth``).

    Returns
    -------
    str or None
        What is outside the region and why it matters; None inside it.

    Examples
    --------
    >>> import core
    >>> print(core.convergence_message(0.1, 0.6))
    None
    >>> print(core.convergence_message(0.1, 0.4))  # doctest: +NORMALIZE_WHITESPACE
    HC is proven to converge only for alpha > 0 and beta > 0.5 (paper, Theorem 5.2): beta 0.4 is not
    above 0.5; many iterations may drift or oscillate
    """
    if in_convergence_region(alpha, beta):
        return None
    reasons = []
    if not alpha > 0.0:
        reasons.append("alpha is 0 (no pull towards the original points)")
    if not beta > 0.5:
        reasons.append(f"beta {beta:g} is not above 0.5")
    return (
        "HC is proven to converge only for alpha > 0 and beta > 0.5 (paper, Theorem 5.2): "
        + " and ".join(reasons)
        + "; many iterations may drift or oscillate"
    )


def convergence_lines(method, alpha, beta):
    """(converges, lines): whether ``method`` (core's name: "hc", "plain", "central", "original") settles on
    a shape that keeps its size, and why, in short lines for a narrow panel (convergence_message is the
    sentence for reports).

    HC: Theorem 5.2 (alpha > 0, beta > 0.5). The Laplacian variants (section 5): plain and central shrink
    towards a point as iterations grow; with the original point and alpha > 0 they converge, but to a
    shrunken compromise (section 3.3).

    Examples
    --------
    >>> from core import convergence_lines
    >>> convergence_lines("hc", 0.1, 0.6)
    (True, ['Converges: α > 0 and β > 0.5', '(paper, Theorem 5.2)'])
    """
    if method == "hc":
        if in_convergence_region(alpha, beta):
            return True, ["Converges: \u03b1 > 0 and \u03b2 > 0.5", "(paper, Theorem 5.2)"]
        lines = ["Outside the convergence region:"]
        if not alpha > 0.0:
            lines.append("\u03b1 = 0: no pull to the original")
        if not beta > 0.5:
            lines.append(f"\u03b2 = {beta:.3g} is not above 0.5")
        lines.append("many iterations may drift")
        return False, lines
    if method == "original" and alpha > 0.0:
        return True, ["Converges (\u03b1 > 0), but shrinks", "part of the way (paper 3.3)"]
    return False, ["Shrinks with every iteration", "(no limit but a point, paper 3.1)"]


def divergence_message(method, alpha, beta, iterations, what):
    """A sentence for users about a run that blew up (``what`` says how), naming the parameters."""
    if method == "hc" and not in_convergence_region(alpha, beta):
        return (
            f"HC with alpha {alpha:g} and beta {beta:g} blew up after {iterations} iterations ({what}): "
            "they lie outside the region where HC converges (alpha > 0 and beta > 0.5, paper Theorem 5.2). "
            "Raise alpha above 0 and beta above 0.5; nothing was changed"
        )
    return f"smoothing ({method}) blew up after {iterations} iterations ({what}); nothing was changed"
