"""Work in slices: a generator yields between its passes (so a caller can show progress and cancel)
and returns its result; these run one to its end, or pass its slices on as progress fractions."""


def to_end(generator):
    """The value ``generator`` returns, run without stopping."""
    while True:
        try:
            next(generator)
        except StopIteration as done:
            return done.value


def as_fraction(generator, fraction):
    """``yield from as_fraction(g, f)``: the value g returns, yielding ``f`` for each of its slices."""
    while True:
        try:
            next(generator)
        except StopIteration as done:
            return done.value
        yield fraction
