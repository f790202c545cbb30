"""The live robot in the page: drawn from its /robot_description at its /joint_states, the path its tip traces,
the simulated bead as deposited, and whether the robot is there at all.

The traced frame is the robot description's own tip (:func:`~ur_glue_planner.studio.robot_geometry.tip_frame_of`:
the dispenser's tip when the dispenser is mounted), so the executed path lies on the bead, not one tool length
above it at ``tool0``.
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import viser

from ur_glue_planner.studio import scene_view as sv
from ur_glue_planner.studio.legend import DEPOSIT_COLOR, EXECUTED_COLOR
from ur_glue_planner.studio.robot_geometry import RobotModel, tip_frame_of
from ur_glue_planner.studio.robot_status import robot_status
from ur_glue_planner.studio.ros_link import MOVED, LiveRobot

TRAIL_STEP = 5e-4  # [m] a new tip path point once the tip has moved this far


class LiveView:
    """What the page shows of the live robot; :meth:`update` each page tick, :meth:`draw_trail` less often.

    Args:
        server: The page's server.
        live: The ROS link to the robot.
        lift: Moves tip path points (K, 3) [m] to where they are drawn (above the glass), or None.
    """

    def __init__(self, server: viser.ViserServer, live: LiveRobot,
                 lift: Callable[[np.ndarray], np.ndarray] | None = None) -> None:
        self.server = server
        self.live = live
        self.lift = lift
        self.view: sv.RobotView | None = None
        self.tip_frame: str | None = None  # the frame traced, once the robot description has arrived
        self.trail: list[np.ndarray] = []
        self.updates = 0  # robot poses sent to the page
        self.bead_points_drawn = 0  # deposit points of the simulated bead shown in the page
        self._urdf: str | None = None
        self._stamp = None
        self._shown: tuple | None = None  # (names, q) of the pose last sent to the page
        self._trail_drawn = 0
        self._pieces: list = []
        self._bead_count = 0
        self._bead_cloud = None

    def update(self) -> None:
        """Draw a new robot description, the newest pose and bead; add the tip to the path."""
        urdf = self.live.urdf()
        if urdf is not None and urdf != self._urdf:
            if self.view is not None:
                self.view.remove()
            self._urdf = urdf
            self.view = sv.RobotView(self.server, '/live', RobotModel(urdf))
            self._shown = None
            self.tip_frame = tip_frame_of(urdf)
        state = self.live.state()
        if self.view is None or state is None or state.stamp == self._stamp:
            return
        self._stamp = state.stamp
        self._draw_bead()
        # A robot at rest still publishes every cycle: its pose goes to the page only when it moved (each pose
        # sent makes every open page render the scene again).
        if (self._shown is not None and self._shown[0] == state.names
                and float(np.max(np.abs(state.q - self._shown[1]))) <= MOVED):
            return
        self._shown = (state.names, np.array(state.q))
        self.view.show(state.names, state.q)
        self.updates += 1
        tip = self.view.robot.frame_position(self.tip_frame, state.names, state.q)
        if tip is not None and (not self.trail or np.linalg.norm(tip - self.trail[-1]) > TRAIL_STEP):
            self.trail.append(tip)

    def status(self, now: float | None = None) -> tuple[str, str]:
        """(state, text) of :func:`robot_status` now (wall time, monotonic [s])."""
        state = self.live.state()
        return robot_status(self.live.prefix, time.monotonic() if now is None else now,
                            None if state is None else state.received, self.live.urdf() is not None)

    def _draw_bead(self) -> None:
        """The simulated bead as it grows: one point per deposit, amber, sized to the bead's mean width."""
        count, bead = self.live.bead()
        if count == self._bead_count or bead is None:
            return
        self._bead_count = count
        if len(bead.points) == 0:
            if self._bead_cloud is not None:
                self._bead_cloud.remove()
                self._bead_cloud = None
            return
        colors = np.tile(np.array([DEPOSIT_COLOR], dtype=np.uint8), (len(bead.points), 1))
        self._bead_cloud = self.server.scene.add_point_cloud(
            '/deposited', points=bead.points.astype(np.float32), colors=colors,
            point_size=float(np.mean(bead.widths)), point_shape='circle')
        self.bead_points_drawn = len(bead.points)

    def draw_trail(self) -> None:
        """Send the new part of the tip path as a piece of its own (the page keeps the earlier pieces)."""
        if len(self.trail) < 2 or len(self.trail) == self._trail_drawn:
            return
        start = max(self._trail_drawn - 1, 0)
        points = np.array(self.trail[start:])
        if self.lift is not None:
            points = self.lift(points)
        self._pieces.append(self.server.scene.add_line_segments(
            f'/executed/piece_{len(self._pieces)}', sv.polyline_segments(points), EXECUTED_COLOR, thickness=0.004))
        self._trail_drawn = len(self.trail)

    def reset_trail(self) -> None:
        """Take the executed path off the page (a new run or plan starts)."""
        self.trail = []
        self._trail_drawn = 0
        for piece in self._pieces:
            piece.remove()
        self._pieces = []

    def clear_bead(self) -> None:
        """Take the deposited bead off the page (a new plan or part: it was laid for the one before); the next bead
        the robot lays is drawn again."""
        if self._bead_cloud is not None:
            self._bead_cloud.remove()
            self._bead_cloud = None
        self.bead_points_drawn = 0

    @property
    def pieces_drawn(self) -> int:
        """Pieces of the executed path on the page."""
        return len(self._pieces)
