"""Keep Sharp Edges' Automatic Amount: how many steps, and how wide a sharpness angle, for the noise
core.mesh.noise finds (the policy beside core.mesh.amount's, which chooses HC's iterations).

Examples
--------
>>> import math
>>> from core.mesh import sharp_amount
>>> sharp_amount.steps_for_noise(0.1, 1000), sharp_amount.steps_for_noise(1.0, 10_000_000)
(6, 1)
>>> round(math.degrees(sharp_amount.angle_for_noise(math.radians(30.0), 0.5)), 1)
66.4
"""

import math

# The Automatic Amount (for a noise of ``ratio`` median edge lengths, core.mesh.noise's estimate):
# * steps: FIRST_STEPS + STEPS_PER_RATIO x ratio, at most MAX_STEPS, and at most WORK_BUDGET / triangles
#   (each step costs NORMAL_ITERATIONS passes over ~6 face pairs per triangle): the error on the tuning
#   parts falls with the steps up to 10 where the noise is heavy, and is flat from 4 to 6 where it is light;
# * angle: at least NOISE_ANGLE_GAIN x atan(ratio): noise tilts neighbouring faces by about that much,
#   and a filter that sees noisy faces as creases leaves the noise (at 1 % noise along the normals on the
#   tuning parts, 50°-60° leave 20-50 % less error than 30°). A crease gentler than the noise is noise.
# * QUIET_RATIO for meshes where no part has noise above core.mesh.noise's threshold (they move within
#   its small radius).
FIRST_STEPS = 4
STEPS_PER_RATIO = 20.0
MAX_STEPS = 10
WORK_BUDGET = 12_000_000  # triangle-steps
NOISE_ANGLE_GAIN = 2.5
QUIET_RATIO = 0.05
CHOOSING_SHARE = 1 / 10  # of a run with the Automatic Amount, the share of its progress the noise estimate takes


def steps_for_noise(ratio, triangles):
    """The Automatic Amount's steps for noise of ``ratio`` median edge lengths on ``triangles`` triangles."""
    wanted = min(MAX_STEPS, round(FIRST_STEPS + STEPS_PER_RATIO * ratio))
    return int(max(1, min(wanted, WORK_BUDGET // max(1, triangles))))


def angle_for_noise(angle, ratio):
    """The Automatic Amount's sharpness angle: ``angle``, or wider where noise of ``ratio`` median edge
    lengths tilts neighbouring faces by more (at most 80°)."""
    return max(angle, min(math.radians(80.0), NOISE_ANGLE_GAIN * math.atan(ratio)))
