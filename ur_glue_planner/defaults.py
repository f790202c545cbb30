"""Default data of the windshield glue job of seed 1 (DESIGN.md section 6)."""

from __future__ import annotations

import math

import numpy as np

#: The 22 waypoints clicked on the seed's windshield [m], world frame, (22, 3), in visiting
#: order. The bead runs up the left edge, right along the top, down the right edge and back
#: along the bottom; the last point lies ~6 mm from the first (a closed bead).
DEFAULT_WAYPOINTS: np.ndarray = np.array([
    [-0.3186, 0.4080, 0.1514], [-0.3350, 0.4932, 0.1720], [-0.3514, 0.5798, 0.1928],
    [-0.3653, 0.6683, 0.2139], [-0.3817, 0.7500, 0.2338], [-0.3948, 0.8153, 0.2496],
    [-0.3158, 0.8263, 0.2447], [-0.2397, 0.8329, 0.2407], [-0.1565, 0.8346, 0.2368],
    [-0.0603, 0.8419, 0.2357], [0.0311, 0.8442, 0.2358], [0.1307, 0.8383, 0.2366],
    [0.3935, 0.8144, 0.2492], [0.3786, 0.7400, 0.2312], [0.3664, 0.6682, 0.2141],
    [0.3538, 0.5981, 0.1972], [0.3207, 0.4120, 0.1525], [0.2180, 0.4132, 0.1473],
    [0.1021, 0.4186, 0.1449], [-0.0568, 0.4185, 0.1441], [-0.1718, 0.4180, 0.1466],
    [-0.3128, 0.4086, 0.1512],
])
DEFAULT_WAYPOINTS.setflags(write=False)

#: Tip-frame orientation at every default waypoint, ZYX Euler angles (z, y, x) [rad] as
#: MATLAB's ``eul2tform([0 0 -pi/3])``; equals Rx(-60 deg).
DEFAULT_ORIENTATION_ZYX: tuple[float, float, float] = (0.0, 0.0, -math.pi / 3.0)

#: Dispensing speed of the tip along the bead [m/s] and the seed's sample time [s].
DEFAULT_TCP_SPEED: float = 0.15
DEFAULT_SAMPLE_TIME: float = 0.02
