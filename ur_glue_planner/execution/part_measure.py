"""Measuring the part before the bead: the cell's scanners (``/ur_sim/part_scan``, sensor_msgs/PointCloud2) read
once, fitted to the nominal glass (``scene/registration.py``), and judged against what the cell corrects.

The scanners' cloud is organised (one row per scanner, one column per beam, NaN where a beam saw nothing) in the
robot's ``base_link``, the planner's world; ur_sim publishes it as a profile scanner's driver would. A cell without
scanners (a real robot without them, ur_sim in a scene without them) has no such topic: the job then runs on the
nominal glass, and says so.
"""
from __future__ import annotations

import time

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import PointCloud2

from ur_glue_planner.scene.registration import CellLimits, Registration, refusal, register
from ur_glue_planner.scene.windshield import WindshieldModel
from ur_glue_planner.scene.windshield_pieces import sample_uv
from ur_sim_driver.description.part_scan import from_cloud

SCAN_TOPIC = 'ur_sim/part_scan'


def read_scan(node: Node, namespace: str = '', timeout: float = 2.0) -> np.ndarray | None:
    """The newest scan (scanners, beams, 3) [m] in base_link, or None when none arrives within ``timeout`` [s] of
    wall time. The subscription lives on a node of its own, spun here (latched: the newest at once)."""
    ns = namespace.strip('/')
    topic = f'/{ns}/{SCAN_TOPIC}' if ns else f'/{SCAN_TOPIC}'
    got: list[PointCloud2] = []
    reader = Node(f'{node.get_name()}_part_scan', context=node.context)
    executor = SingleThreadedExecutor(context=node.context)
    try:
        reader.create_subscription(PointCloud2, topic, got.append,
                                   QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        executor.add_node(reader)
        deadline = time.monotonic() + timeout
        while not got and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=min(0.05, max(deadline - time.monotonic(), 0.0)))
    finally:
        executor.shutdown()
        reader.destroy_node()
    return from_cloud(got[0]) if got else None


def measure_part(profiles: np.ndarray, nominal: WindshieldModel, limits: CellLimits | None = None
                 ) -> tuple[Registration | None, str | None]:
    """The part fitted to ``nominal`` and the reason it is refused (None: accepted); (None, reason) when too little
    was seen to fit at all."""
    try:
        found = register(profiles, nominal)
    except ValueError as exc:
        return None, str(exc)
    return found, refusal(found, limits or CellLimits())


def describe(found: Registration) -> str:
    """One line of what the measurement found [mm, deg]."""
    d = found.describe()
    bend = float(np.abs(found.shape_deviation(sample_uv(found.model, 0.02))).max())
    return (f"part measured: offset {d['offset_mm']} mm, turned {d['rotation_deg']} deg, bent up to "
            f"{1e3 * bend:.2f} mm; fit residual {d['face_rms_mm']:.3f} mm rms on "
            f"{d['face_points']} points, edges {d['edge_rms_mm']:.3f} mm rms on {d['edge_points']}")
