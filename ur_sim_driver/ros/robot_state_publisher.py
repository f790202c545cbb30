"""robot_state_publisher: the robot's URDF and its frames on TF, as the ROS node of that name does.

``/robot_description`` and ``/tf_static`` (the fixed joints) are published once, transient local; ``/tf``
carries the six arm joints' transforms at ``publish_frequency`` [Hz] of simulated time, from the joint
positions of the control cycle, stamped with its time. Frames and joints come from the same kinematic tree
the URDF and the MuJoCo model are built from (``description/urdf.py``); every frame carries the tf_prefix.
"""
from __future__ import annotations

import math

import numpy as np
from geometry_msgs.msg import TransformStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from scipy.spatial.transform import Rotation
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from ur_common.quaternions import quat_from_matrix
from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import JointSpec, build_urdf, kinematic_tree

_Z = np.array([0.0, 0.0, 1.0])


def _transform(joint: JointSpec) -> TransformStamped:
    """The joint's transform at position 0: parent -> child = the joint origin."""
    tf = TransformStamped()
    tf.header.frame_id = joint.parent
    tf.child_frame_id = joint.child
    t = tf.transform.translation
    t.x, t.y, t.z = (float(v) for v in joint.origin.xyz)
    w, x, y, z = quat_from_matrix(joint.origin.matrix()[:3, :3])
    r = tf.transform.rotation
    r.x, r.y, r.z, r.w = float(x), float(y), float(z), float(w)
    return tf


class RobotStatePublisher(Component):
    """/robot_description, /tf_static and /tf of the simulated arm (and its tool)."""

    name = 'robot_state_publisher'
    type_name = 'robot_state_publisher'  # a node of the driver's launch file, not a controller
    is_controller = False

    def on_configure(self, host: Host, node: Node) -> None:
        sim, cfg = host.sim, host.cfg
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        # Relative to the namespace, as upstream's; /tf and /tf_static are absolute, as tf2_ros's.
        self._pub_description = node.create_publisher(String, cfg.prefixed('robot_description'), latched)
        self._pub_static = node.create_publisher(TFMessage, '/tf_static', latched)
        self._pub_tf = node.create_publisher(TFMessage, '/tf', 100)
        self._period = 1.0 / cfg.publish_frequency
        self._next = 0.0
        # Simulated time is a sum of physics steps, a hair off the multiples of the period: half a control
        # period of slack keeps the publishing on the cycle nearest each multiple.
        self._slack = 0.5 * sim.control_dt

        # The description of the type the driver is configured for: the robot's own only when the two agree (with
        # verify_robot_model off a mismatch runs, and /tf is then as wrong as the driver's would be).
        described = load_ur_params(cfg.ur_type)
        tree = kinematic_tree(described, cfg.tf_prefix, get_tool(cfg.tool))
        stamp = host.clock.stamp(sim.time)
        static = []
        for joint in tree:
            if joint.index is None:
                tf = _transform(joint)
                tf.header.stamp = stamp
                static.append(tf)
        moving = sorted((j for j in tree if j.index is not None), key=lambda j: j.index)
        # Each moving transform is origin * Rz(q) (UR joints turn about their z); the translation does not depend on q.
        self._origins = Rotation.from_matrix(np.array([j.origin.matrix()[:3, :3] for j in moving]))
        self._index = np.array([j.index for j in moving], dtype=np.intp)
        # Published as CDR bytes patched in place (cdr_template.py): the rotations and stamps change.
        self._tf = CdrTemplate(
            TFMessage(transforms=[_transform(j) for j in moving]),
            stamps=tuple(f'transforms[{k}].header.stamp' for k in range(len(moving))),
            floats=tuple(f'transforms[{k}].transform.rotation.{a}' for k in range(len(moving)) for a in 'xyzw'),
            publisher=self._pub_tf)

        urdf = sim.urdf if described is sim.params else build_urdf(described, cfg.tf_prefix, get_tool(cfg.tool))
        self._pub_description.publish(String(data=urdf))
        self._pub_static.publish(TFMessage(transforms=static))

    def update(self, cycle: Cycle) -> None:
        t = cycle.t + self._slack
        if t < self._next:
            return
        self._next = (math.floor(t / self._period) + 1) * self._period
        if not self._tf.listened():
            return
        turns = Rotation.from_rotvec(cycle.state.q[self._index, None] * _Z)
        rotations = (self._origins * turns).as_quat()  # (k, 4), (x, y, z, w) as ROS orders them
        self._tf.publish(rotations.reshape(-1), cycle.stamp_parts)

