"""The robot's force mode as a pure function (``motion/force_mode.py``): the force frame of each type and the
compliant axes' velocity (free space: up to the speed limit; at the requested force: no drive; damping; the other
axes never move)."""
import numpy as np
import pytest

from ur_sim_driver.motion.force_mode import ForceModeSpec, admittance_step, force_frame

pytestmark = pytest.mark.timeout(30)


def spec(kind: int = 2, frame: np.ndarray | None = None, damping: float = 0.1, gain: float = 1.0,
         limit: float = 0.05) -> ForceModeSpec:
    return ForceModeSpec(np.eye(4) if frame is None else frame, np.array([False, False, True, False, False, False]),
                         np.array([0.0, 0.0, 10.0, 0.0, 0.0, 0.0]), kind, np.full(6, limit), damping, gain)


def test_the_force_frame_of_each_type():
    frame = np.eye(4)
    frame[:3, 3] = (0.5, 0.0, 0.0)
    tcp = np.array([0.0, 0.0, 0.0])
    assert np.allclose(force_frame(spec(2, frame), tcp, np.zeros(3)), np.eye(3))
    r = force_frame(spec(1, frame), tcp, np.zeros(3))  # y from the TCP towards the frame's origin
    assert np.allclose(r[:, 1], [1.0, 0.0, 0.0]) and np.allclose(r.T @ r, np.eye(3)) and np.linalg.det(r) > 0
    r = force_frame(spec(3, frame), tcp, np.array([0.0, 0.2, 0.3]))  # x along the velocity in the x-y plane
    assert np.allclose(r[:, 0], [0.0, 1.0, 0.0]) and np.allclose(r[:, 2], [0.0, 0.0, 1.0])
    assert np.allclose(force_frame(spec(3, frame), tcp, np.zeros(3)), np.eye(3))  # at rest: as given


def test_free_space_accelerates_to_the_speed_limit_on_the_compliant_axis_only():
    s, v = spec(damping=0.0), np.zeros(6)
    for _ in range(5000):  # 10 s at 500 Hz
        v = admittance_step(s, v, np.zeros(6), 0.002)
    assert v[2] == pytest.approx(0.05) and not np.any(np.delete(v, 2))


def test_at_the_requested_force_no_drive_and_damping_stops_the_tcp():
    s = spec(damping=1.0)
    v = admittance_step(s, np.array([0.0, 0.0, 0.04, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 10.0, 0, 0, 0]), 0.002)
    assert 0.0 < v[2] < 0.04 * np.exp(-0.19)  # decays at 100 /s
    still = np.zeros(6)
    for _ in range(100):
        still = admittance_step(spec(damping=0.5), still, np.array([0.0, 0.0, 10.0, 0, 0, 0]), 0.002)
    assert not np.any(still)


def test_gain_scaling_scales_the_drive():
    once = [admittance_step(spec(gain=g, damping=0.0, limit=10.0), np.zeros(6), np.zeros(6), 0.002)[2]
            for g in (0.5, 1.0, 2.0)]
    assert once[1] == pytest.approx(2 * once[0]) and once[2] == pytest.approx(4 * once[0])
