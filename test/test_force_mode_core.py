"""The robot's force mode as a pure function (``motion/force_mode.py``): the force frame of each type, the
compliant axes' velocity (free space: up to the speed limit; at the requested force: no drive; damping; the other
axes never move), and the deviation limits of the non-compliant axes (a deviation within holds, one beyond is the
robot's stop, per axis, translations and rotations, measured along the force frame's axes)."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ur_sim_driver.motion.force_mode import (
    AXES,
    ForceModeSpec,
    admittance_step,
    deviation,
    deviation_cause,
    force_frame,
    rotation_vector,
)

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


DEVIATION_LIMITS = np.array([0.002, 0.003, 0.004, 0.01, 0.02, 0.03])  # [m, rad] a different limit per axis
TILTED = Rotation.from_euler('zyx', [0.7, -0.4, 1.1]).as_matrix()  # a force frame not aligned with base


def held(selection=(False,) * 6) -> ForceModeSpec:
    """Force mode in the TILTED task frame with the deviation limits on the axes not in `selection`."""
    frame = np.eye(4)
    frame[:3, :3] = TILTED
    return ForceModeSpec(frame, np.array(selection), np.zeros(6), 2, DEVIATION_LIMITS.copy(), 0.025, 0.5)


def pose(rotation: np.ndarray, position) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rotation, position
    return t


PROGRAM = pose(Rotation.from_rotvec([0.3, -2.0, 0.5]).as_matrix(), [0.4, -0.2, 0.3])  # where the program holds it


def deviated(axis: int, amount: float) -> np.ndarray:
    """PROGRAM moved by `amount` [m] along, or turned by `amount` [rad] about, the force frame's axis `axis`."""
    direction = TILTED[:, axis % 3]
    if axis < 3:
        return pose(PROGRAM[:3, :3], PROGRAM[:3, 3] + amount * direction)
    return pose(Rotation.from_rotvec(amount * direction).as_matrix() @ PROGRAM[:3, :3], PROGRAM[:3, 3])


@pytest.mark.parametrize('axis', range(6), ids=AXES)
@pytest.mark.parametrize('sign', (1.0, -1.0), ids=('positive', 'negative'))
def test_a_deviation_within_the_limit_holds_and_one_beyond_stops(axis, sign):
    spec, limit = held(), DEVIATION_LIMITS[axis]
    for within in (0.0, 0.5 * limit, 0.99 * limit):
        d = deviation(TILTED, deviated(axis, sign * within), PROGRAM)
        assert d[axis] == pytest.approx(sign * within, abs=1e-9) and np.allclose(np.delete(d, axis), 0.0, atol=1e-9)
        assert deviation_cause(spec, d) is None
    cause = deviation_cause(spec, deviation(TILTED, deviated(axis, sign * 1.01 * limit), PROGRAM))
    assert cause is not None
    name, unit, scale = (AXES[axis], 'mm', 1e3) if axis < 3 else (AXES[axis][1], 'rad', 1.0)
    assert ('along ' if axis < 3 else 'about ') + name in cause
    assert f'(limit {limit * scale:.{2 if axis < 3 else 4}f} {unit})' in cause
    assert cause.count('(limit ') == 1  # only the axis beyond its limit is named


def test_the_compliant_axes_are_not_held_to_a_deviation():
    for axis in range(6):
        selection = np.arange(6) == axis
        d = deviation(TILTED, deviated(axis, 10.0 * DEVIATION_LIMITS[axis]), PROGRAM)
        assert deviation_cause(held(tuple(selection)), d) is None  # its limit is a speed
        assert deviation_cause(held(), d) is not None


def test_the_deviation_is_measured_along_the_force_frame_not_base():
    # 3 mm along base x in a force frame turned 90 degrees about z: along the frame's -y, whose limit is 3 mm
    turned = Rotation.from_euler('z', 90, degrees=True).as_matrix()
    frame = np.eye(4)
    frame[:3, :3] = turned
    spec = ForceModeSpec(frame, np.zeros(6, bool), np.zeros(6), 2, DEVIATION_LIMITS.copy(), 0.025, 0.5)
    d = deviation(turned, pose(PROGRAM[:3, :3], PROGRAM[:3, 3] + [0.0029, 0.0, 0.0]), PROGRAM)
    assert d[:3] == pytest.approx([0.0, -0.0029, 0.0], abs=1e-12)
    assert deviation_cause(spec, d) is None  # base x's 2 mm limit does not apply
    cause = deviation_cause(spec, deviation(turned, pose(PROGRAM[:3, :3], PROGRAM[:3, 3] + [0.0031, 0.0, 0.0]),
                                            PROGRAM))
    assert '-3.10 mm along y' in cause


def test_several_axes_beyond_are_all_named():
    actual = pose(deviated(4, 0.05)[:3, :3], deviated(0, -0.01)[:3, 3])
    cause = deviation_cause(held(), deviation(TILTED, actual, PROGRAM))
    assert '-10.00 mm along x' in cause and '+0.0500 rad about y' in cause


@pytest.mark.parametrize('angle', (0.0, 1e-9, 1e-3, 0.5, 2.0, np.pi - 1e-3, np.pi - 1e-6, np.pi))
def test_rotation_vector_matches_scipy(angle):
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    v = rotation_vector(Rotation.from_rotvec(angle * axis).as_matrix())
    if angle < np.pi - 1e-6:
        assert v == pytest.approx(angle * axis, abs=1e-9)
    else:  # a half turn about a and about -a are the same rotation
        assert min(np.linalg.norm(v - angle * axis), np.linalg.norm(v + angle * axis)) < 1e-6
