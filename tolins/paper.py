"""Constants of the paper's insertion task (CoRL 2020, "Experiment Setup").

Order of the 4-vectors: action ``[ux, uy, utheta, uz]``, pose ``[x, y, theta, z]``.
Units: mm, rad, s.
"""

from __future__ import annotations

import numpy as np

#: Control period (s).
CONTROL_DT = 0.25
#: Episode horizon k_max (control steps).
HORIZON = 40
#: Success reward scale c in c (1 - k / k_max).
SUCCESS_REWARD = 100.0
#: Reward of a step with a collision.
COLLISION_REWARD = -1.0
#: Action limits a_max ``[mm/s, mm/s, rad/s, mm/s]``.
A_MAX = np.array([2.5, 2.5, 0.1, 2.5])
#: Measurement-noise std of the pose ``[mm, mm, rad, mm]``.
POSE_NOISE_STD = np.array([0.1, 0.1, 0.0, 0.1])
