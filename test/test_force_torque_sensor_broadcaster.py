"""force_torque_sensor_broadcaster over DDS: the wrench at rest is the tool's (and payload's) weight in
tool0_controller, zero_ftsensor zeroes it, and a contact with the floor shows up.

The expected weight is computed independently of MuJoCo: the tool0 orientation from Pinocchio's forward
kinematics of our URDF at the joint state of the same stamp, gravity 9.81 m/s^2 along -z of base_link.
"""
import threading

import numpy as np
import pinocchio as pin
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import JointState
from sim_harness import following, point, running_sim, wait_for

from ur_sim_driver.description.tool import DISPENSER
from ur_sim_driver.robot.payload import make_payload

G = np.array([0.0, 0.0, -9.81])  # [m/s^2] in base_link (MuJoCo's default gravity; base_link is the world)
TILTED = [0.4, -1.1, 1.2, -0.6, 1.0, 0.3]  # tool0 tilted on every axis: every wrench component non-zero
# Tool pointing straight down with the dispenser tip 30 mm above the floor, and 20 mm below it (ur5e).
ABOVE_FLOOR = [0.0, -1.3532, 2.054, -2.2715, -1.5708, 0.0]
INTO_FLOOR = [0.0, -1.2594, 2.101, -2.4124, -1.5708, 0.0]
TOOL_COM = DISPENSER.mount.matrix()[:3, :3] @ np.array(DISPENSER.com)  # [m] in tool0


def stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


class Streams:
    """/joint_states and ~/wrench received, keyed by stamp [ns]."""

    def __init__(self, h) -> None:
        self.lock = threading.Lock()
        self.q: dict[int, np.ndarray] = {}
        self.wrench: dict[int, np.ndarray] = {}
        self.frames: set[str] = set()
        p = h.sim.cfg.prefixed
        h.listen(JointState, p('joint_states'), self._on_js)
        h.listen(WrenchStamped, p('force_torque_sensor_broadcaster/wrench'), self._on_wrench)

    def _on_js(self, msg) -> None:
        with self.lock:
            self.q[stamp_ns(msg)] = np.array(msg.position)

    def _on_wrench(self, msg) -> None:
        f, t = msg.wrench.force, msg.wrench.torque
        with self.lock:
            self.wrench[stamp_ns(msg)] = np.array([f.x, f.y, f.z, t.x, t.y, t.z])
            self.frames.add(msg.header.frame_id)

    def newest_wrench(self) -> float | None:
        """The stamp [s] of the newest wrench received (None before the first)."""
        with self.lock:
            return max(self.wrench) * 1e-9 if self.wrench else None

    def pair_after(self, t_ns: int) -> tuple[np.ndarray, np.ndarray]:
        """The latest (joint positions, wrench) of one stamp after `t_ns`."""
        def found():
            with self.lock:
                common = [s for s in self.wrench if s > t_ns and s in self.q]
            return max(common) if common else None
        wait_for(lambda: found() is not None, what='a wrench and a joint state of the same stamp')
        s = found()
        with self.lock:
            return self.q[s], self.wrench[s]


def expected_wrench(urdf: str, q, loads) -> np.ndarray:
    """Force and torque [N, N m] in tool0 about its origin that `loads` [(mass, com in tool0)] exert at `q`."""
    model = pin.buildModelFromXML(urdf)
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q))
    r = data.oMf[model.getFrameId('tool0')].rotation
    out = np.zeros(6)
    for mass, com in loads:
        weight = r.T @ (mass * G)
        out += np.r_[weight, np.cross(com, weight)]
    return out


def relative_error(measured, expected) -> tuple[float, float]:
    """Largest force and torque component errors, relative to the size of the expected force and torque."""
    e = measured - expected
    return (np.abs(e[:3]).max() / np.linalg.norm(expected[:3]), np.abs(e[3:]).max() / np.linalg.norm(expected[3:]))


def test_wrench_at_rest_is_the_weight_and_zero_ftsensor_zeroes_it():
    with running_sim(tool='dispenser', initial_positions=TILTED) as h:
        streams = Streams(h)
        q, w = streams.pair_after(0)
        assert streams.frames == {'tool0_controller'}
        tool = [(DISPENSER.mass, TOOL_COM)]
        expected = expected_wrench(h.sim.sim.urdf, q, tool)
        ef, et = relative_error(w, expected)
        print(f'tool weight: expected {np.round(expected, 5)}, measured {np.round(w, 5)}; '
              f'error force {100 * ef:.2e} %, torque {100 * et:.2e} %')
        assert ef < 0.01 and et < 0.01

        payload_cog = np.array([0.01, -0.02, 0.12])
        payload = make_payload(2.0, payload_cog, np.array([0.004, 0.004, 0.002, 0.0, 0.0, 0.0]))
        with h.sim.host.lock:
            h.sim.sim.mount(payload)  # what a hand would do: set_payload only changes the robot's belief
            t_set = round(h.sim.sim.time * 1e9)
        h.wait_sim_time(0.5)  # the arm settles under the new load
        q, w = streams.pair_after(round(h.sim.sim.time * 1e9) - 1)
        assert t_set > 0
        expected = expected_wrench(h.sim.sim.urdf, q, [*tool, (2.0, payload_cog)])
        ef, et = relative_error(w, expected)
        print(f'tool + 2 kg payload: expected {np.round(expected, 5)}, measured {np.round(w, 5)}; '
              f'error force {100 * ef:.2e} %, torque {100 * et:.2e} %')
        assert np.linalg.norm(w[:3]) > 4 * DISPENSER.mass * 9.81  # the weight grew 5-fold
        assert ef < 0.01 and et < 0.01

        # The robot told of the payload (set_payload) takes its weight off the reading: the tool's is left.
        with h.sim.host.lock:
            h.sim.sim.set_payload(payload.mass, payload.cog, payload.inertia)
            t_set = round(h.sim.sim.time * 1e9)
        q, w = streams.pair_after(t_set)
        ef, et = relative_error(w, expected_wrench(h.sim.sim.urdf, q, tool))
        assert ef < 0.01 and et < 0.01

        with h.sim.host.lock:
            h.sim.sim.zero_ftsensor()
            t_zero = round(h.sim.sim.time * 1e9)
        _, w = streams.pair_after(t_zero)
        assert np.abs(w).max() < 1e-6


def test_a_contact_with_the_floor_shows_up():
    with running_sim(tool='dispenser', initial_positions=ABOVE_FLOOR) as h:
        streams = Streams(h)
        _, w_free = streams.pair_after(0)
        # tool0 points straight down here: its z is -z of the world, so the weight is +z in tool0.
        np.testing.assert_allclose(w_free[:3], [0.0, 0.0, DISPENSER.mass * 9.81], atol=1e-3)
        h.wait_sim_time(0.2)
        # every wrench of the contact is seen: the simulation waits for the listener (a loaded machine's transport
        # lost the peak once)
        with following(streams.newest_wrench):
            handle = h.send(h.goal([point(INTO_FLOOR, 2.0, np.zeros(6))]))
            assert handle.accepted
            h.result(handle)  # whatever the outcome: the floor is in the way
            h.wait_sim_time(0.2)
        with streams.lock:
            fz = np.array([w[2] for s, w in sorted(streams.wrench.items())])
        # The floor pushes the tool up, the tool the arm: the force on the arm along tool0 z (down) drops from
        # the weight to below it by the contact force.
        contact = DISPENSER.mass * 9.81 - fz.min()
        print(f'largest contact force with the floor: {contact:.1f} N')
        assert contact > 5.0
