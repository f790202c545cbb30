"""In step with a client (``pace_topic``): the simulation loop waits for the robot time the client last handled.

A client that must act on the robot's clock (the glue planner switching its gun on the trajectory's time) publishes
the robot time it has handled on ``pace_topic`` (rosgraph_msgs/Clock, stamped on ur_sim's clock). The loop does not
run more than ``pace_lag`` past it, so what the client sends in reply arrives within ``pace_lag`` of robot time
however loaded the machine is (``docs/parts.md``).
"""
from __future__ import annotations

import threading

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

from ur_sim_driver.motion.conversions import RobotClock

# The client's last word counts, also if it was said before ur_sim subscribed (a client may start first).
PACE_QOS = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
STOP_POLL = 0.05  # [s] of wall time between looks at the stop event while held


class PaceGate:
    """The robot time [s] a client last published on `topic`, and the loop's wait for it.

    Args:
        node: subscribes `topic` (its callback only stores the time and wakes the loop).
        topic: the pace topic.
        clock: the stamps' clock (the client publishes robot time as it read it from the stamps).
        lag: [s] of robot time the loop may run past the client's time.
    """

    def __init__(self, node: Node, topic: str, clock: RobotClock, lag: float) -> None:
        self._clock = clock
        self._lag = lag
        self._paced: float | None = None  # None before the client's first message
        self._changed = threading.Condition()
        node.create_subscription(Clock, topic, self._on_pace, PACE_QOS)

    @property
    def paced_until(self) -> float | None:
        """The simulated time [s] the client last published, None before its first message."""
        with self._changed:
            return self._paced

    def _on_pace(self, msg: Clock) -> None:
        with self._changed:
            self._paced = self._clock.sim_time(msg.clock)  # the newest, even if earlier: a client may hold back
            self._changed.notify_all()

    def wait(self, last_published: float, dt: float, stop: threading.Event) -> None:
        """Hold the loop while the cycle published last (`last_published` [s]) is more than the lag past the time
        the client last published. Until the client's first message the loop runs at about real time's pace
        (one control period `dt` [s] of wall time per cycle): its clients find it, and it burns no core
        meanwhile."""
        with self._changed:
            if self._paced is None:
                self._changed.wait(dt)  # a message ends the wait early
                return
            while not stop.is_set() and last_published > self._paced + self._lag + 1e-9:
                self._changed.wait(STOP_POLL)  # woken by the client's next message; the timeout sees a stop
