"""force_mode_controller over DDS in lockstep: upstream's refusals (inactive, zero quaternion, unknown frame, type,
damping, gain scaling) and its scenario (a task frame in tool0_controller, 10 N along a compliant axis: the TCP moves
along that axis and holds the others), pressing on the floor with the requested force, and force mode ending with
stop_force_mode and with the controller's deactivation (the robot then holds still where it was), and the deviation
limits: a push on the arm (``/ur_sim/apply_wrench``) that deviates a non-compliant axis within its limit changes
nothing, one beyond it is the robot's protective stop, recovered from as a user does (unlock protective stop)."""
import numpy as np
import pytest
from cm_helpers import ControllerManagerClient
from geometry_msgs.msg import WrenchStamped
from scipy.spatial.transform import Rotation
from sim_harness import SETTLED_SPEED, point, running_sim, wait_answer, wait_for, wait_still
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import SafetyMode
from ur_msgs.srv import SetForceMode

from ur_sim_driver.description.analytic_ik import UrAnalyticIK, nearest_branch
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.robot.robot_state import NORMAL, PROTECTIVE_STOP

pytestmark = pytest.mark.timeout(300)
NAME = 'force_mode_controller'
SCALED = 'scaled_joint_trajectory_controller'
READY = np.array([0.0, -1.2, 1.2, -1.57, -1.57, 0.0])  # [rad] the tool pointing down, the flange 46 cm up
AWAY = [-1.6, -1.55, -1.7, -1.0, 2.05, 0.5]  # [rad] upstream's test pose, away from singularities


@pytest.fixture(scope='module')
def rig():
    with running_sim(tool='dispenser') as h:  # its nozzle touches the floor: the force sensor feels it
        cm = ControllerManagerClient(h)
        start = h.client.create_client(SetForceMode, f'/{NAME}/start_force_mode')
        stop = h.client.create_client(Trigger, f'/{NAME}/stop_force_mode')
        wait_still(lambda: start.service_is_ready() and stop.service_is_ready(), what='the force mode services')
        yield h, cm, start, stop


def request(frame: str = 'base', q=(0.0, 0.0, 0.0, 1.0), axes=(False, False, True, False, False, False),
            force=(0.0, 0.0, 10.0), kind: int = 2, speed: float = 1.0, damping: float = 0.1,
            gain: float = 0.8) -> SetForceMode.Request:
    r = SetForceMode.Request()
    r.task_frame.header.frame_id = frame
    o = r.task_frame.pose.orientation
    o.x, o.y, o.z, o.w = q
    (r.selection_vector_x, r.selection_vector_y, r.selection_vector_z, r.selection_vector_rx,
     r.selection_vector_ry, r.selection_vector_rz) = axes
    r.wrench.force.x, r.wrench.force.y, r.wrench.force.z = force
    r.type = kind
    r.speed_limits.linear.x = r.speed_limits.linear.y = r.speed_limits.linear.z = speed
    r.speed_limits.angular.x = r.speed_limits.angular.y = r.speed_limits.angular.z = speed
    r.deviation_limits = [1.0] * 6
    r.damping_factor, r.gain_scaling = damping, gain
    return r


def call(client, req):
    return wait_answer(client.call_async(req), 'the force mode answer')


def tcp(h) -> tuple[np.ndarray, np.ndarray]:
    """The TCP (tool0) position [m] and rotation (3, 3) in the base frame."""
    with h.sim.host.lock:
        position, quat = h.sim.sim.tcp_pose()
    return position.copy(), Rotation.from_quat(quat).as_matrix()


def in_charge(cm) -> None:
    assert cm.switch(activate=[NAME], deactivate=[SCALED]).ok


def test_refusals_as_upstream(rig):
    h, cm, start, stop = rig
    log = h.rosout()
    assert not call(start, request()).success  # the controller is inactive
    in_charge(cm)
    assert not call(start, request(q=(0.0, 0.0, 0.0, 0.0))).success
    assert not call(start, request(frame='nonexisting6t54')).success
    for kind in (0, 4):
        assert not call(start, request(kind=kind)).success
    for damping, gain in ((-0.1, 0.8), (1.1, 0.8), (0.1, -0.1), (0.1, 2.1)):
        assert not call(start, request(damping=damping, gain=gain)).success
    for damping, gain in ((0.0, 0.8), (1.0, 0.8), (0.1, 0.0), (0.1, 2.0)):  # the bounds are allowed
        assert call(start, request(force=(0.0, 0.0, 0.0), damping=damping, gain=gain)).success
        assert call(stop, Trigger.Request()).success
    texts = ("Can't accept new requests. Controller is not running.",
                 'Received task frame with all-zeros quaternion. It should have at least one non-zero entry.',
                 'Could not transform nonexisting6t54 to robot base',
                 'The force mode type has to be 1, 2, or 3. Received 4',
                 'The damping factor has to be between 0 and 1. Received 1.100000',
                 'The gain scaling has to be between 0 and 2. Received 2.100000')
    wait_still(lambda: all(any(n == NAME and t.startswith(x) for n, t in log) for x in texts), what='the log lines')


def test_free_space_the_tcp_moves_along_the_compliant_axis_only(rig):
    h, cm, start, stop = rig
    _move(h, AWAY)
    in_charge(cm)
    p0, r0 = tcp(h)
    # upstream's scenario: the task frame is tool0_controller turned 90 degrees about its x axis, so its z axis is
    # the tool's -y; 10 N along it, nothing to push against
    half = np.sqrt(0.5)
    assert call(start, request(frame='tool0_controller', q=(half, 0.0, 0.0, half))).success
    h.wait_sim_time(5.0)
    p1, _ = tcp(h)
    moved = r0.T @ (p1 - p0)  # in the tool's axes as they were
    assert moved[1] < -0.03 and abs(moved[0]) < 1e-3 and abs(moved[2]) < 1e-3
    assert call(stop, Trigger.Request()).success
    held, _ = tcp(h)
    h.wait_sim_time(0.5)
    assert np.linalg.norm(tcp(h)[0] - held) < 2e-3  # stops within the damping's time
    assert cm.switch(activate=[SCALED], deactivate=[NAME]).ok


def test_pressing_on_the_floor_settles_at_the_requested_force(rig):
    h, cm, start, stop = rig
    ik = UrAnalyticIK(h.sim.sim.params.dh, base_pose=np.diag([-1.0, -1.0, 1.0, 1.0]))  # the controller's base
    above = ik.fk(READY)
    above[2, 3] = get_tool('dispenser').tip_in_tool0()[2, 3] + 0.03  # [m] the nozzle 3 cm above the floor
    solutions = ik.solve(above)
    _move(h, solutions[nearest_branch(solutions, READY)[0]])
    in_charge(cm)
    assert call(start, request(force=(0.0, 0.0, -10.0), speed=0.05, damping=0.2, gain=1.0)).success  # down
    h.wait_sim_time(10.0)
    forces = []
    for _ in range(50):
        h.wait_sim_time(0.02)
        with h.sim.host.lock:
            forces.append(h.sim.sim.wrench()[:3].copy())
    r = tcp(h)[1]
    pushed = -(r @ np.mean(forces, axis=0))  # what the tool applies to the floor, base axes
    assert pushed[2] == pytest.approx(-10.0, abs=1.5) and np.std([-(r @ f)[2] for f in forces]) < 1.0
    assert h.sim.robot.safety_mode == 1  # no protective stop
    assert call(stop, Trigger.Request()).success
    assert cm.switch(activate=[SCALED], deactivate=[NAME]).ok


def _move(h, q) -> None:
    """To `q`, and at rest there: a switch away from the trajectory controller while the arm still moves would brake
    it (stopj) from where it is, beyond `q`."""
    handle = h.send(h.goal([point(q, 4.0)]))
    assert handle.accepted and h.result(handle)[1] == 0
    wait_for(lambda: float(np.max(np.abs(h.sim.sim.state().qd))) < SETTLED_SPEED, what='the arm at rest')


def test_deactivation_ends_force_mode_and_the_robot_holds_still(rig):
    h, cm, start, stop = rig
    in_charge(cm)
    assert call(start, request(force=(0.0, 0.0, 5.0))).success
    h.wait_sim_time(0.5)
    assert cm.switch(deactivate=[NAME]).ok
    h.wait_sim_time(0.5)
    z0 = tcp(h)[0][2]
    h.wait_sim_time(0.5)
    assert abs(tcp(h)[0][2] - z0) < 1e-6
    assert cm.switch(activate=[SCALED]).ok


# A push on wrist_3_link (not felt by the flange's sensor, so compliance does not yield to it): what it deviates the
# held TCP by, measured with this robot's servo at AWAY: 20 N along base y about 0.11 mm along y, 80 N about 0.44 mm;
# a torque of 2 N m about base z about 0.004 rad about z, 8 N m about 0.016 rad.
PUSHES = {
    'translation': ([0.25e-3] * 3 + [0.05] * 3, (0.0, 20.0, 0.0, 0.0, 0.0, 0.0), (0.0, 80.0, 0.0, 0.0, 0.0, 0.0),
                    'mm along y (limit 0.25 mm)'),
    'rotation': ([1e-3] * 3 + [0.01] * 3, (0.0, 0.0, 0.0, 0.0, 0.0, 2.0), (0.0, 0.0, 0.0, 0.0, 0.0, 8.0),
                 'rad about z (limit 0.0100 rad)'),
}


def push(h, publisher, log, wrench) -> None:
    """Push wrist_3_link with `wrench` (force [N], torque [N m]; base axes) from now until the next push, the
    simulation held still until ur_sim has taken it (its log line)."""
    msg = WrenchStamped()
    msg.header.frame_id = 'wrist_3_link'
    f, t = msg.wrench.force, msg.wrench.torque
    f.x, f.y, f.z, t.x, t.y, t.z = wrench
    seen = len(log)
    publisher.publish(msg)
    wait_still(lambda: any(n == 'ur_sim_wrench' and x.startswith('push on wrist_3_link') for n, x in log[seen:]),
               what='the push taken')


@pytest.fixture(scope='module')
def pusher(rig):
    """A publisher on ``/ur_sim/apply_wrench`` (it lives as long as the client node)."""
    h = rig[0]
    publisher = h.client.create_publisher(WrenchStamped, '/ur_sim/apply_wrench', 10)
    wait_still(lambda: publisher.get_subscription_count() > 0, what='the apply_wrench subscriber')
    return publisher


@pytest.mark.parametrize('case', PUSHES)
def test_a_deviation_beyond_the_limit_is_a_protective_stop(rig, pusher, case):
    h, cm, start, stop = rig
    limits, within, beyond, text = PUSHES[case]
    robot, force_mode = h.sim.robot, h.sim._force_mode
    log = h.rosout()
    safety = []
    stop_listening = h.listen(SafetyMode, '/io_and_status_controller/safety_mode', lambda m: safety.append(m.mode),
                              latched=True)
    try:
        _move(h, AWAY)
        h.wait_sim_time(1.0)  # at rest: the hold starts without the trajectory's last motion
        wait_for(lambda: safety, what='the latched safety mode')
        in_charge(cm)
        req = request(force=(0.0, 0.0, 0.0))  # compliant along z, pushing nothing: every other axis held
        req.deviation_limits = limits
        assert call(start, req).success

        push(h, pusher, log, within)
        h.wait_sim_time(1.0)
        assert robot.safety_mode == NORMAL and force_mode.spec is not None and safety[-1] == SafetyMode.NORMAL

        push(h, pusher, log, beyond)
        wait_for(lambda: robot.safety_mode == PROTECTIVE_STOP, timeout=0.5, what='the protective stop')
        assert 'force mode' in robot.stop_cause and text in robot.stop_cause
        assert robot.stop_cause.count('(limit ') == 1  # the one axis pushed beyond
        wait_for(lambda: safety[-1] == SafetyMode.PROTECTIVE_STOP and not force_mode.active,
                 what='the stop published and the controller_stopper having deactivated force_mode_controller')
        assert force_mode.spec is None  # force mode ended with the stop
        push(h, pusher, log, (0.0,) * 6)  # the hand lets go: the arm stays where it stopped
        h.wait_sim_time(0.5)
        held = tcp(h)[0]
        h.wait_sim_time(0.5)
        assert np.linalg.norm(tcp(h)[0] - held) < 1e-5

        refused = h.keeper.call('unlock_protective_stop')  # within 5 s of the stop the robot refuses
        assert not refused.success and robot.safety_mode == PROTECTIVE_STOP
        wait_for(lambda: robot.unlock_wait() == 0.0, what='the 5 s before a protective stop may be unlocked')
        assert h.keeper.call('unlock_protective_stop').success
        wait_for(lambda: safety[-1] == SafetyMode.NORMAL, what='NORMAL published')
        assert not robot.program_running  # the stop paused the program: the driver (headless) sends it again
        assert h.keeper.call('resend_robot_program').success
        wait_for(lambda: force_mode.active, what="the controller_stopper's activating force_mode_controller again")
        assert force_mode.spec is None  # its activation does not restart force mode
        h.wait_sim_time(0.5)
        assert np.linalg.norm(tcp(h)[0] - held) < 1e-5
        assert any(n == NAME and x.startswith('PROTECTIVE_STOP: force mode') and text in x for n, x in log)
        assert call(start, req).success  # force mode starts again, the robot holds within the limits
        h.wait_sim_time(0.5)
        assert robot.safety_mode == NORMAL and force_mode.spec is not None
        assert call(stop, Trigger.Request()).success
        assert cm.switch(activate=[SCALED], deactivate=[NAME]).ok
    finally:
        push(h, pusher, log, (0.0,) * 6)
        stop_listening()


def test_a_urscript_program_runs_the_same_force_mode(rig):
    """force_mode from a program (as ur_rtde's forceMode sends it): the robot's one force mode, whatever the
    controller's state; 10 N up along the base's z axis in free space moves the TCP up, and only up; the program's
    end_force_mode, then its end, leave the arm held."""
    h, _, _, _ = rig
    _move(h, AWAY)
    p0, _ = tcp(h)
    with h.sim.host.lock:
        h.sim.host.scripts.submit('''def press():
  force_mode_set_damping(0.1)
  force_mode_set_gain_scaling(0.8)
  force_mode(p[0, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 0, 10, 0, 0, 0], 2, [1, 1, 1, 1, 1, 1])
  sleep(5.0)
  end_force_mode()
  sleep(0.5)
end''')
    wait_for(lambda: h.sim.host.scripts.current is None, timeout=60.0, what='the program to end')
    p1, _ = tcp(h)
    moved = p1 - p0
    assert moved[2] > 0.03 and abs(moved[0]) < 1e-3 and abs(moved[1]) < 1e-3, moved
    assert h.sim.robot.safety_mode == 1 and h.sim._force_mode.spec is None
    h.wait_sim_time(0.5)
    assert np.linalg.norm(tcp(h)[0] - p1) < 2e-3  # held
