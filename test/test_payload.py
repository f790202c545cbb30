"""Payload at the flange: validation, principal axes, the joint efforts at rest a mounted payload adds (against
Pinocchio's gravity torques of our URDF with the payload on tool0), and set_payload as the controller's belief: it
moves nothing, and is taken off the force-torque reading."""
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.robot.payload import make_payload
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator

# A pose with long lever arms for the payload (forearm out, wrist turned) and joint 1 off zero.
POSE = (0.4, -1.1, 1.2, -0.6, 1.0, 0.3)
PAYLOAD = dict(mass=3.0, cog=np.array([0.02, -0.03, 0.08]),
               inertia=np.array([0.012, 0.015, 0.009, 0.001, -0.002, 0.0015]))


def hold(sim: Simulator, q, cycles: int) -> np.ndarray:
    """Hold `q` for `cycles` control cycles; the efforts of the last state [N m]."""
    q = np.asarray(q, dtype=float)
    for _ in range(cycles):
        state = sim.state()
        sim.advance(state, TrajectorySample(q, np.zeros(6), np.zeros(6), 0, True))
    state = sim.state()
    assert np.abs(state.qd).max() < 1e-6, 'not at rest'
    return state.effort


def pinocchio_gravity(urdf: str, q, payload=None) -> np.ndarray:
    """Generalised gravity [N m] of the URDF, with `payload` (mass, cog, inertia) rigidly on tool0."""
    model = pin.buildModelFromXML(urdf)
    if payload is not None:
        frame = model.frames[model.getFrameId('tool0')]
        xx, yy, zz, xy, xz, yz = payload['inertia']
        tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        inertia = pin.Inertia(payload['mass'], payload['cog'], tensor)
        model.appendBodyToJoint(frame.parentJoint, inertia, frame.placement)
    data = model.createData()
    return pin.computeGeneralizedGravity(model, data, np.asarray(q, dtype=float))


def mounted(tool: str = 'none', **payload) -> Simulator:
    params = {'tool': tool, 'initial_positions': list(POSE)}
    if payload:
        params.update({'mounted_payload.mass': payload['mass'], 'mounted_payload.cog': list(payload['cog']),
                       'mounted_payload.inertia': list(payload['inertia'])})
    return Simulator(sim_config_from_params(params))


@pytest.mark.parametrize('tool', ['none', 'dispenser'])
def test_a_mounted_payload_changes_efforts_at_rest_by_its_gravity_torque_and_set_payload_does_not(tool):
    without, loaded = mounted(tool), mounted(tool, **PAYLOAD)
    before, after = hold(without, POSE, 500), hold(loaded, POSE, 500)
    expected = pinocchio_gravity(loaded.urdf, POSE, PAYLOAD) - pinocchio_gravity(loaded.urdf, POSE)
    assert np.linalg.norm(expected) > 5.0  # the pose gives the payload real leverage
    # Per joint within 1 % of the largest change (joint 1 carries no gravity torque about its vertical axis).
    err = np.abs((after - before) - expected).max() / np.abs(expected).max()
    print(f'payload {tool}: expected {np.round(expected, 4)}, measured {np.round(after - before, 4)}, '
          f'max error {100 * err:.2e} %')
    assert err < 0.01
    # Telling the robot of a payload mounts nothing.
    without.set_payload(**PAYLOAD)
    np.testing.assert_allclose(hold(without, POSE, 500), before, atol=1e-9 * np.abs(before).max())


@pytest.mark.parametrize('believed', [0.0, 1.0, 3.0, 4.5])
def test_the_wrench_reads_the_mounted_payload_less_the_believed_one(believed):
    """A free arm with 3 kg mounted reads the weight of 3 kg less what the robot believes: about zero with the
    right belief, the difference with a wrong one, as a UR's compensated force-torque reading does."""
    sim = mounted(**PAYLOAD)
    hold(sim, POSE, 500)
    sim.set_payload(believed, PAYLOAD['cog'], PAYLOAD['inertia'] if believed else np.zeros(6))
    force, torque = sim.wrench()[:3], sim.wrench()[3:]
    assert np.linalg.norm(force) == pytest.approx(abs(PAYLOAD['mass'] - believed) * 9.81, abs=1e-6)
    np.testing.assert_allclose(torque, np.cross(PAYLOAD['cog'], force), atol=1e-9)
    # the residual force is the difference's weight: straight down in the base frame
    rot = Rotation.from_quat(sim.tcp_pose()[1])
    np.testing.assert_allclose(rot.apply(force), [0.0, 0.0, -(PAYLOAD['mass'] - believed) * 9.81], atol=1e-6)


def test_zero_ftsensor_keeps_the_compensation():
    sim = mounted(**PAYLOAD)
    hold(sim, POSE, 200)
    sim.zero_ftsensor()
    assert np.abs(sim.wrench()).max() < 1e-9
    sim.set_payload(**PAYLOAD)  # now believed: its weight comes off the (zeroed) reading
    assert np.linalg.norm(sim.wrench()[:3]) == pytest.approx(PAYLOAD['mass'] * 9.81, abs=1e-6)


def test_a_bad_mounted_payload_names_the_parameters():
    with pytest.raises(ConfigError) as info:
        sim_config_from_params({'mounted_payload.mass': -1.0})
    assert "'mounted_payload.*'" in str(info.value) and 'mass = -1.0 kg is outside [0, 100.0] kg' in str(info.value)


def test_the_state_is_untouched_by_set_payload():
    sim = Simulator(sim_config_from_params({'initial_positions': list(POSE)}))
    hold(sim, POSE, 10)
    t, q = sim.time, sim.state().q
    sim.set_payload(**PAYLOAD)
    assert sim.time == t
    np.testing.assert_array_equal(sim.state().q, q)
    assert sim.payload.mass == 3.0


def test_invalid_payload_is_refused_and_the_old_one_kept():
    sim = Simulator(sim_config_from_params({}))
    sim.set_payload(1.0, np.zeros(3), np.zeros(6))
    with pytest.raises(ConfigError, match='mass'):
        sim.set_payload(-1.0, np.zeros(3), np.zeros(6))
    assert sim.payload.mass == 1.0
    assert sim.physics.model.body('payload').mass[0] == 0.0  # a belief: nothing was mounted


@pytest.mark.parametrize('args, field', [
    ((float('nan'), (0, 0, 0)), 'mass'),
    ((101.0, (0, 0, 0)), 'mass'),
    ((1.0, (0, 0)), 'centre of gravity'),
    ((1.0, (0, 0, float('inf'))), 'centre of gravity'),
    ((1.0, (0, 0, 6.0)), 'centre of gravity'),
    ((1.0, (0, 0, 0), (1, 1, 1)), 'inertia'),
    ((1.0, (0, 0, 0), (-0.1, 0.1, 0.1, 0, 0, 0)), 'positive semi-definite'),
    ((1.0, (0, 0, 0), (0.01, 0.01, 0.05, 0, 0, 0)), 'rigid body'),
])
def test_make_payload_names_the_bad_field(args, field):
    with pytest.raises(ConfigError, match=field):
        make_payload(*args)


def test_principal_axes_rebuild_the_tensor():
    rng = np.random.default_rng(3)
    for _ in range(50):
        # A random rigid body: moments obeying the triangle inequality, turned by a random rotation.
        a, b = rng.uniform(0.001, 0.05, 2)
        moments = np.array([a, b, rng.uniform(abs(a - b), a + b)])
        rot = pin.exp3(rng.normal(size=3))
        t = rot @ np.diag(moments) @ rot.T
        payload = make_payload(1.0, (0, 0, 0), (t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]))
        diag, wxyz = payload.principal()
        r = pin.Quaternion(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).toRotationMatrix()
        assert np.linalg.det(r) == pytest.approx(1.0)
        np.testing.assert_allclose(r @ np.diag(diag) @ r.T, t, atol=1e-12)
    diag, wxyz = make_payload(1.0, (0, 0, 0)).principal()  # a point mass
    np.testing.assert_array_equal(diag, np.zeros(3))
