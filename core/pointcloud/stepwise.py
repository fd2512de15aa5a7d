"""Long stages in slices: generators that yield the fraction of their own work done between slices
and return their result, so that a caller showing progress (core.pointcloud.PointCloudSmoother.steps)
updates every second or so at a million points; callers that want the result only run them with
core.slices.to_end.
"""

# Elements of work (kNN entries, crossing edges, incidences) between two yields: a second or so of
# NumPy work. Below it a stage runs as one slice, so small clouds yield once per stage.
SLICE = 1 << 23


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
