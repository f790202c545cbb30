"""The plan's bead tip path as nav_msgs/Path on a latched topic of the planner's own, for viewers and the run's bag.

``<namespace>/ur_glue_planner/planned_path`` (transient local, depth 1): one pose per bead sample (the sample time
of the job, 0.02 s by default), the dispenser tip along the bead segment's motion (its flying start's run-up and
run-out included), in the robot's ``base_link`` (the planner's world: the robot at the origin), with the driver's
tf_prefix when it has one.
"""
from __future__ import annotations

import weakref

import numpy as np
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from ur_glue_planner.execution import ros_conversions as conv
from ur_glue_planner.motion.plan import GluePlan

PLANNED_PATH = 'ur_glue_planner/planned_path'  # below the job's namespace
FIRST_JOINT = 'shoulder_pan_joint'
LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)

_publishers: weakref.WeakKeyDictionary[Node, Publisher] = weakref.WeakKeyDictionary()


def planned_path_topic(prefix: str = '') -> str:
    """The topic under `prefix` ('' or e.g. '/ur10', as the driver's topics)."""
    return f'{prefix}/{PLANNED_PATH}'


def tf_prefix_of(joint_names: tuple[str, ...] | list[str]) -> str:
    """The driver's tf_prefix, read off its joint names ('my_ur_shoulder_pan_joint' -> 'my_ur_'); '' if none."""
    for name in joint_names:
        if name.endswith(FIRST_JOINT):
            return name[:-len(FIRST_JOINT)]
    return ''


def planned_path(plan: GluePlan, frame_id: str = 'base_link', stamp: float = 0.0) -> Path:
    """The bead segment's tip poses (positions [m], orientations) in `frame_id`, every pose stamped `stamp` [s]."""
    bead = plan.bead
    msg = Path()
    msg.header.frame_id = frame_id
    msg.header.stamp = conv.stamp(stamp)
    pos = np.asarray(bead.tip_pos, dtype=float)
    quat = np.asarray(bead.tip_quat, dtype=float)  # w first
    for p, q in zip(pos, quat):
        pose = PoseStamped()
        pose.header = msg.header
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = (float(v) for v in p)
        o = pose.pose.orientation
        o.w, o.x, o.y, o.z = (float(v) for v in q)
        msg.poses.append(pose)
    return msg


def publish_planned_path(node: Node, prefix: str, plan: GluePlan, frame_id: str, stamp: float) -> str:
    """Publish the plan's path (latched) from `node`; the publisher is made once per node and kept with it.
    Returns the topic."""
    topic = planned_path_topic(prefix)
    publisher = _publishers.get(node)
    if publisher is None or publisher.topic_name != topic:
        publisher = node.create_publisher(Path, topic, LATCHED)
        _publishers[node] = publisher
    publisher.publish(planned_path(plan, frame_id, stamp))
    return topic
