"""An external force-torque sensor fed through RTDE, as URScript's ``ft_rtde_input_enable`` sets one up.

While enabled, the robot's force-torque reading (``Simulator.wrench``: RTDE ``actual_TCP_force`` and
``ft_raw_wrench``, ``get_tcp_force``, the force-torque broadcaster, force mode, tool contact) comes from the RTDE
input ``external_force_torque`` instead of the arm's own sensor. The client writes the sensor's raw measurement in
the sensor's frame: the tool flange's axes, about the sensor's measuring point; the controller takes the believed
payload's weight and the zero off it as it does from its own sensor (forum.universal-robots.com, "Payload
compensation with RTDE force injection").

The sensor's mass and centre of gravity are kept as the controller's model of the tool; ur_sim's arm carries what the
configuration mounts (``mounted_payload``), so they change nothing it simulates.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ur_sim_driver.errors import ConfigError

MAX_SENSOR_MASS = 100.0  # [kg] as a payload's bound (payload.MAX_MASS)
MAX_OFFSET = 5.0  # [m] distance of the measuring point or centre of gravity from the flange


@dataclass(frozen=True, eq=False)
class ExternalFtSensor:
    """An enabled external sensor.

    Attributes:
        mass: [kg] the sensor's mass.
        measuring_offset: (3,) the measuring point in tool0 [m].
        cog: (3,) the sensor's centre of gravity in tool0 [m].
    """

    mass: float
    measuring_offset: np.ndarray
    cog: np.ndarray

    def at_flange(self, reading: np.ndarray) -> np.ndarray:
        """(6,) `reading` (force [N], torque [N m] about the measuring point, tool0 axes) moved to the tool0
        origin: the torque of the force applied at the measuring point is added."""
        force = reading[:3]
        return np.concatenate((force, reading[3:] + np.cross(self.measuring_offset, force)))


def make_external_ft(mass: float, measuring_offset, cog) -> ExternalFtSensor:
    """A validated sensor; ConfigError names the value and its limit."""
    if not np.isfinite(mass) or not 0.0 <= mass <= MAX_SENSOR_MASS:
        raise ConfigError(f'sensor_mass = {mass} kg is outside [0, {MAX_SENSOR_MASS}]')
    vectors = {}
    for name, value in (('sensor_measuring_offset', measuring_offset), ('sensor_cog', cog)):
        v = np.array(value, dtype=float)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ConfigError(f'{name} = {value} is not 3 finite numbers [m]')
        if np.linalg.norm(v) > MAX_OFFSET:
            raise ConfigError(f'{name} = {v.tolist()} is more than {MAX_OFFSET} m from the flange')
        vectors[name] = v
    return ExternalFtSensor(float(mass), vectors['sensor_measuring_offset'], vectors['sensor_cog'])
