"""Convergence of the smoothers (paper section 5): the proven region and the messages about it."""


class ConvergenceWarning(UserWarning):
    """HC was asked to run with (alpha, beta) outside the region where Theorem 5.2 proves convergence."""


class DivergenceError(ValueError):
    """A run blew up (non-finite coordinates, or a bounding box many times the input's): nothing is
    returned, so no caller can write the garbage. Only possible outside the convergence region."""


def in_convergence_region(alpha, beta):
    """Theorem 5.2: the HC algorithm converges for alpha > 0 and beta > 0.5."""
    return alpha > 0.0 and beta > 0.5


def convergence_message(alpha, beta):
    """A sentence for users about where (alpha, beta) lies; None inside the proven region."""
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


def divergence_message(method, alpha, beta, iterations, what):
    """A sentence for users about a run that blew up (``what`` says how), naming the parameters."""
    if method == "hc" and not in_convergence_region(alpha, beta):
        return (
            f"HC with alpha {alpha:g} and beta {beta:g} blew up after {iterations} iterations ({what}): "
            "they lie outside the region where HC converges (alpha > 0 and beta > 0.5, paper Theorem 5.2). "
            "Raise alpha above 0 and beta above 0.5; nothing was changed"
        )
    return f"smoothing ({method}) blew up after {iterations} iterations ({what}); nothing was changed"
