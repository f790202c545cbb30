"""The joints' motor currents as a UR reports them, and the torques it reports as "current as torque".

A UR measures each joint's motor current, not its torque: RTDE ``actual_current`` [A], the primary interface's joint
data, and the UR driver's effort state interface (``hardware_interface.cpp`` ``read()`` copies ``actual_current``
into the joint efforts). A current is the torque the drive delivers at the joint divided by the joint's torque
constant (motor constant times gear ratio, ``drives.torque_constant`` of the type file, with its provenance): all of
the torque the drive delivers, to hold the arm and payload up, to accelerate them, against friction and contact.

The simulation's actuator torques are that torque but for one part: in the servo's modes ur_sim leaves the joints'
Coulomb friction out of the physics (the servo cancels it exactly, ``Simulator._servo_friction``); on a robot the
motor delivers it, so it is added back here, with its sign smoothed over ``COULOMB_VELOCITY`` (a joint at rest needs
none). Under torque control the physics feels the part the robot's compensation leaves, and the actuator torques
already hold the compensated part.

From 5.23.0 / 10.11.0 a UR also reports ``actual_current_as_torque``: the drive torque less what gravity needs with
the payload the robot believes in (the driver's ``use_currents_as_efforts: false``; 0 at rest with no external load
and the payload set right).
"""
from __future__ import annotations

import numpy as np

from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.simulator import Simulator

COULOMB_VELOCITY = 0.01  # [rad/s] joint speed over which the friction's sign goes from 0 to +-0.76 (tanh)


def drive_torques(effort: np.ndarray, qd: np.ndarray, coulomb: np.ndarray, cancelled: bool,
                  effort_max: np.ndarray) -> np.ndarray:
    """(n,) [N m] the torques the drives deliver: the simulation's actuator torques `effort`, plus the Coulomb
    friction `coulomb` (n,) [N m] against the joint speeds `qd` (n,) [rad/s] where the simulation `cancelled` it,
    within the drives' limits `effort_max` (n,) [N m] (the friction added back counts against them too)."""
    effort = np.asarray(effort, dtype=float)
    if not cancelled:
        return effort
    friction = np.asarray(coulomb) * np.tanh(np.asarray(qd) / COULOMB_VELOCITY)
    return np.clip(effort + friction, -effort_max, effort_max)


def currents(torques: np.ndarray, torque_constant: np.ndarray) -> np.ndarray:
    """(n,) [A] the motor currents that deliver `torques` (n,) [N m] through joints of `torque_constant` [N m/A]."""
    return np.asarray(torques, dtype=float) / np.asarray(torque_constant)


def simulated_drive_torques(sim: Simulator, state: ArmState | None = None) -> np.ndarray:
    """(n,) [N m] what the simulated robot's drives deliver now (the last physics step's; `state`: the simulator's
    state now, if the caller has it)."""
    state = sim.state() if state is None else state
    p = sim.params
    return drive_torques(state.effort, state.qd, p.coulomb, sim.coulomb_cancelled, p.effort_max)


def motor_currents(sim: Simulator, state: ArmState | None = None) -> np.ndarray:
    """(n,) [A] the simulated robot's motor currents now (RTDE ``actual_current``)."""
    return currents(simulated_drive_torques(sim, state), sim.params.torque_constant)


def current_as_torque(sim: Simulator, state: ArmState | None = None) -> np.ndarray:
    """(n,) [N m] the drive torques less the robot's gravity compensation (its believed payload and gravity): RTDE
    ``actual_current_as_torque``, about 0 for a joint at rest without an external load."""
    return simulated_drive_torques(sim, state) - sim.gravity_compensation()
