"""Shared facts and helpers of the seed 2 (UR10 ROS course) example scripts.

Run the simulator first:  ur_sim --ros-args --params-file config/seed_ur10.yaml
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ur_glue_planner.client import URClient
from ur_glue_planner.orientation import rotation_from_zyx_euler

NAMESPACE = '/ur10'
CONTROLLER = 'vel_based_pos_traj_controller'
Q_HOME = np.zeros(6)
T_HOME = 2.5  # [s]
T_OFFSET = 0.5  # [s] the seed's pause after a move
T_TARGET = 6.5  # [s] the seed records (T_TARGET + 0.5) s = 7 s at 50 Hz (N = 350)
RATE = 50.0  # [Hz] recording rate of the seed
# Task 3 (IK): target pose of ee_link in the seed's world, where the robot base stands 1.0 m up.
TARGET_POSITION = np.array([0.6, 0.0, 1.0])
TARGET_ZYX = (np.pi / 4, np.pi / 4, -np.pi / 4)
BASE_IN_WORLD = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 1.0], [0, 0, 0, 1.0]])
IK_WEIGHTS = np.ones(6)
IK_GUESS = np.array([0.0, 1.0, -2.0, 2.0, 1.0, 1.0])
SEED_IK_ANSWER = np.array([-0.3824, 0.9804, -2.0033, 2.22, 0.8626, 1.3279])
# Tasks 12 and 14: via points at 2.5 s and 6.0 s.
VIA_TIMES = np.array([2.5, 6.0])
QF = np.array([-1.0, 0.0, -1.0, 1.0, 0.0, 2.0])
QVEL_TASK14 = np.array([-0.4, 0.0, 0.0, -0.3, 0.0, 0.0])


def target_pose() -> np.ndarray:
    """The seed's tformTargetPose = trvec2tform(p) * eul2tform(zyx) (4, 4)."""
    pose = np.eye(4)
    pose[:3, :3] = rotation_from_zyx_euler(*TARGET_ZYX)
    pose[:3, 3] = TARGET_POSITION
    return pose


def target_configuration(ur: URClient) -> np.ndarray:
    """Task 3: IK of ee_link to the seed's target from the seed's initial guess."""
    result = ur.ik(target_pose(), q0=IK_GUESS, frame='ee_link', weights=IK_WEIGHTS, base_pose=BASE_IN_WORLD)
    if not result.converged:
        raise RuntimeError(f'IK did not converge: residual {result.residual_pos:.2e} m, {result.residual_rot:.2e} rad')
    return result.q


def go_home(ur: URClient) -> None:
    """The seed's homing: the home configuration on the topic, then a pause of t_home + t_offset."""
    ur.publish_trajectory([T_HOME], Q_HOME[None, :], np.zeros((1, 6)))
    ur.sleep(T_HOME + T_OFFSET)


DELIVERY = 1.0  # [s] of wall time for a trajectory to reach the controller: one that arrives after its start is
# sampled past it (a jump), and a loaded machine has delayed a topic message by more than 0.3 s


def start_time(ur: URClient) -> float:
    """A trajectory start stamp in the future, in robot time [s], so a recording can be anchored to it."""
    return ur.start_time(delivery=DELIVERY)


def parse_args(description: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument('--out', type=Path, default=Path('out') / 'seed2', help='where PNG plots go')
    parser.add_argument('--timeout', type=float, default=15.0, help='connection timeout [s]')
    return parser.parse_args()


def connect(timeout: float = 15.0, **kwargs) -> URClient:
    """A client on the seed preset's names."""
    return URClient(namespace=NAMESPACE, controller_name=CONTROLLER, timeout=timeout, **kwargs)
