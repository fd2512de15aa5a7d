"""Long stages in slices: generators that yield the fraction of their own work done between slices
and return their result, so that a caller showing progress (core.pointcloud.PointCloudSmoother.steps)
updates every second or so at a million points, and ``drain`` for callers that want the result only.
"""

# Elements of work (kNN entries, crossing edges, incidences) between two yields: a second or so of
# NumPy work. Below it a stage runs as one slice, so small clouds yield once per stage.
SLICE = 1 << 23


def drain(steps):
    """Run a stepwise generator to its end; its return value."""
    while True:
        try:
            next(steps)
        except StopIteration as stop:
            return stop.value


class Slices:
    """Counts the work done since the last yield: ``due(work)`` adds ``work`` and says whether a
    slice's worth has been done since (and if so starts counting afresh)."""

    def __init__(self):
        self.work = 0

    def due(self, work):
        self.work += int(work)
        if self.work < SLICE:
            return False
        self.work = 0
        return True
