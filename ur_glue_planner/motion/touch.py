"""A touch move: the tip goes straight along the tool axis onto a surface point and on into it.

Not part of a glue job: it is the move that tests and benchmarks of the robot's contact handling use (the
protective stop of ur_sim, a tool-contact detection), planned like the job's descent so that the tip meets
the surface at a known speed and orientation.
"""
from __future__ import annotations

import numpy as np

from ur_glue_planner.motion.approach import JointSegment, offset_pose, tool_axis_move
from ur_glue_planner.motion.kinematics import Kinematics


def touch_move(kin: Kinematics, q_surface: np.ndarray, axis: np.ndarray, height: float, depth: float,
               speed: float, dt: float) -> JointSegment:
    """Tip move from `height` [m] before a surface point to `depth` [m] beyond it, along the tool axis.

    Args:
        kin: Tip kinematics.
        q_surface: (n,) joint positions with the tip on the surface point [rad].
        axis: Tool axis (3,) in the tip frame (the direction the nozzle points).
        height, depth: [m] > 0.
        speed: Peak tip speed [m/s], reached halfway, i.e. at the surface when height == depth.
        dt: Sample time [s].

    Raises:
        PlanningError: IK fails along the way.
    """
    beyond = offset_pose(kin.fk(q_surface), axis, -depth)  # moved back by -depth: into the surface
    q_beyond = kin.ik_or_raise(beyond, q_surface, f'the point {depth * 1e3:.1f} mm beyond the surface')
    return tool_axis_move(kin, q_beyond, beyond, axis, height + depth, speed, dt, toward_anchor=True,
                          name='touch')
