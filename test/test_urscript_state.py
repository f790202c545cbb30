"""URScript's state, kinematics and mode functions on the simulated robot (no ROS): what a program reads of the arm
(actual and target joints and TCP, history, forward and inverse kinematics, Jacobian and its rate, mass matrix,
Coriolis torques, limits, steadiness), the payload and force-mode settings it makes, and the modes it switches
(teach mode, the sensor's zero, gravity, a protective stop, an external force-torque sensor fed through RTDE)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from script_box import READY, Box

from ur_sim_driver.robot.robot_state import PLAYING, PROTECTIVE_STOP, STOPPED
from ur_sim_driver.urscript.state_functions import pose_sub
from ur_sim_driver.urscript.values import Pose, pose_add


def _values(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.strip('p[]').split(',')])


def test_state_and_kinematics_read_what_the_arm_does():
    box = Box()
    target = [float(v) for v in np.add(READY, [0.3, 0.0, 0.0, 0.0, 0.0, 0.0])]
    box.run(f'''def prog():
  textmsg(get_steptime())
  textmsg(is_steady())
  textmsg(get_tcp_offset())
  before = get_actual_joint_positions()
  movej({target}, a=1.4, v=1.05)
  sync()
  textmsg(get_actual_joint_positions_history(0) == get_actual_joint_positions())
  textmsg(get_target_joint_positions())
  textmsg(get_forward_kin())
  textmsg(get_forward_kin(before))
  textmsg(get_inverse_kin_has_solution(get_forward_kin(before)))
  textmsg(get_inverse_kin_has_solution(p[3, 0, 0, 0, 0, 0]))
  textmsg(is_within_safety_limits([0, 0, 0, 0, 0, 7]))
  textmsg(is_within_safety_limits({target}))
  speedj([0.2, 0, 0, 0, 0, 0], a=2.0, t=0.3)
  textmsg(is_steady())
  textmsg(get_target_joint_speeds())
  textmsg(get_target_tcp_speed())
  stopj(2.0)
end''')
    assert not box.errors(), box.errors()
    log = box.log
    assert log[0] == '0.002' and log[1] == 'True' and log[2] == 'p[0, 0, 0, 0, 0, 0]'
    assert log[3] == 'True'
    assert np.allclose(_values(log[4]), target, atol=1e-6)
    program_ik = box.runner.compile('textmsg(1)\n')
    at_target = Pose.from_matrix(program_ik.ik.fk(np.array(target)))
    assert np.allclose(_values(log[5]), at_target.values, atol=1e-3)
    assert np.allclose(_values(log[6]), Pose.from_matrix(program_ik.ik.fk(np.array(READY))).values, atol=1e-5)
    assert log[7:11] == ['True', 'False', 'False', 'True']
    assert log[11] == 'False'  # moving
    assert _values(log[12])[0] == pytest.approx(0.2, abs=1e-6)
    twist = _values(log[13])  # the TCP speed of joint 1 turning at 0.2 rad/s: about the base z axis
    assert twist[5] == pytest.approx(0.2, abs=1e-6) and np.linalg.norm(twist[3:5]) < 1e-6


def test_dynamics_jacobian_and_its_rate():
    box = Box()
    box.run('''def prog():
  textmsg(get_mass_matrix())
  textmsg(get_coriolis_and_centrifugal_torques())
  textmsg(get_jacobian())
  speedj([0.5, 0.5, 0, 0, 0, 0], a=5.0, t=0.2)
  textmsg(get_coriolis_and_centrifugal_torques())
  textmsg(get_jacobian_time_derivative())
  textmsg(get_target_joint_accelerations())
  stopj(5.0)
end''')
    assert not box.errors(), box.errors()

    def matrix(text):
        return np.array(eval(text))  # noqa: S307 (a list of lists of numbers written by textmsg)
    mass = matrix(box.log[0])
    assert mass.shape == (6, 6) and np.allclose(mass, mass.T) and np.all(np.linalg.eigvalsh(mass) > 0)
    assert np.abs(matrix(box.log[1])).max() < 1e-9  # at rest
    jacobian = matrix(box.log[2])
    assert jacobian.shape == (6, 6) and jacobian[5, 0] == pytest.approx(1.0)  # joint 1 turns about the base z
    assert np.abs(matrix(box.log[3])).max() > 1e-3  # moving: Coriolis and centrifugal torques
    assert np.abs(matrix(box.log[4])).max() > 1e-3
    assert np.allclose(matrix(box.log[5]), 0.0)  # at constant speed


def test_payload_force_settings_and_pose_sub():
    box = Box()
    box.run('''def prog():
  set_target_payload(1.5, [0, 0.01, 0.05], [0.01, 0.01, 0.01, 0, 0, 0])
  textmsg(get_target_payload())
  textmsg(get_target_payload_cog())
  textmsg(get_target_payload_inertia())
  force_mode_set_gain_scaling(0.5)
  force_mode_set_damping(0.025)
end''')
    assert box.log == ['1.5', '[0, 0.01, 0.05]', '[0.01, 0.01, 0.01, 0, 0, 0]']
    a, b = Pose((0.1, 0.2, 0.3, 0.1, -0.2, 0.3)), Pose((0.4, -0.1, 0.2, -0.3, 0.2, 0.1))
    assert np.allclose(pose_add(pose_sub(a, b), b).values, a.values)
    for source, reason in [('force_mode_set_damping(2)', 'damping is a number in [0, 1]'),
                           ('force_mode_set_gain_scaling(-1)', 'scaling is a number in [0, 2]'),
                           ('set_target_payload(-1, [0, 0, 0])', 'm is a number in [0, 1000]')]:
        box = Box()
        box.run(f'def prog():\n  {source}\nend')
        assert reason in box.errors()[0].text


def _pushed(box: Box, program: str) -> np.ndarray:
    """Run `program` while wrist_3 is pushed sideways with 30 N for its first 0.3 s; the joints at every cycle."""
    body = box.sim.physics.body_id('wrist_3_link')
    steps = []

    def push():
        steps.append(None)
        force = [0.0, 30.0, 0.0] if len(steps) <= 150 else [0.0, 0.0, 0.0]
        box.sim.physics.set_external_wrench(body, np.array(force), np.zeros(3))
    box.before_step = push
    box.run(program)
    assert not box.errors(), box.errors()
    return np.array(box.q)


def test_teach_mode_lets_a_push_move_the_arm_and_it_holds_where_it_ends():
    held = _pushed(Box(), 'def prog():\n  sleep(0.6)\nend')
    assert np.abs(held - READY).max() < 0.01  # the servo holds against the push
    box_dt = 0.002
    q = _pushed(Box(), 'def prog():\n  teach_mode()\n  sleep(0.6)\n  end_teach_mode()\n  sleep(1.0)\nend')
    assert np.abs(q[300] - READY).max() > 0.05  # free: the push moved it
    assert np.abs(q[-1] - q[-51]).max() < 1e-4  # after end_teach_mode the robot brings it to rest and holds it
    # near where teach mode ended: it stopped as hard as the robot brakes (10 rad/s^2) from the speed it had
    speed = np.abs(q[300] - q[299]).max() / box_dt
    assert np.abs(q[-1] - q[300]).max() < speed ** 2 / (2 * 10.0) + 0.01
    box = Box()
    box.run('def prog():\n  freedrive_mode()\n  movej([0, -1.2, 1.2, -1.57, -1.57, 0])\nend')
    assert 'the robot is in freedrive' in box.errors()[0].text


def test_zero_ftsensor_gravity_and_protective_stop():
    box = Box()
    box.run('''def prog():
  zero_ftsensor()
  set_gravity([0, 0, 9.82])
end''')
    assert not box.errors()
    assert np.abs(box.sim.wrench()).max() < 0.5
    assert np.allclose(box.sim.gravity_belief, [0, 0, 9.82])
    box = Box()
    took = box.run('def prog():\n  protective_stop()\n  sleep(1)\nend')
    assert box.robot.safety_mode == PROTECTIVE_STOP and took < 0.01  # the robot stopped the program at once
    assert box.robot.program_state != PLAYING


def test_set_tcp_moves_the_tcp_that_poses_moves_and_the_robot_report():
    box = Box()
    box.run('''def prog():
  start = get_actual_tcp_pose()
  set_tcp(p[0, 0, 0.1, 0, 0, 0.5])
  textmsg(get_tcp_offset())
  textmsg(pose_dist(start, get_actual_tcp_pose()))
  textmsg(pose_dist(start, get_actual_tool_flange_pose()))
  target = pose_trans(get_actual_tcp_pose(), p[0.05, 0.02, 0, 0, 0, 0])
  movel(target, a=1.0, v=0.1)
  textmsg(pose_dist(get_actual_tcp_pose(), target))
end''')
    assert not box.errors(), box.errors()
    assert box.log[0] == 'p[0, 0, 0.1, 0, 0, 0.5]'
    assert float(box.log[1]) == pytest.approx(0.1, abs=1e-9) and float(box.log[2]) < 1e-9
    assert float(box.log[3]) < 1e-3
    # the robot reports the same TCP (what RTDE, the primary interface and /tf tool0_controller read)
    program = box.runner.compile('textmsg(1)\n')
    position, _ = box.sim.tcp_pose()
    assert np.allclose(position, program.forward_kin(box.sim.state().q, None).values[:3], atol=1e-4)
    # the TCP, not tool0, went along a straight line
    points = np.array([program.forward_kin(q, None).values[:3] for q in box.q[2:]])
    line = (points[-1] - points[0]) / np.linalg.norm(points[-1] - points[0])
    off = (points - points[0]) - np.outer((points - points[0]) @ line, line)
    assert np.abs(off).max() < 2e-4
    assert np.allclose(box.sim.tcp_offset, [0, 0, 0.1, 0, 0, 0.5])


def test_target_waypoint_joint_torques_and_freedrive_status():
    box = Box()
    far = [float(v) for v in np.add(READY, [0.5, 0.0, 0.0, 0.0, 0.0, 0.0])]
    box.run(f'''def prog():
  thread watcher():
    sleep(0.3)
    textmsg(pose_dist(get_target_waypoint(), get_forward_kin({far})) < 1e-6)
    textmsg(pose_dist(get_target_tcp_pose(), get_forward_kin({far})) > 0.01)
  end
  sleep(0.5)
  textmsg(norm(get_joint_torques()) < 1e-6)
  set_payload(2.0, [0, 0, 0.05])
  sleep(0.5)
  textmsg(get_joint_torques()[1] > 5)
  textmsg(get_freedrive_status())
  run watcher()
  movej({far}, a=1.0, v=0.5)
  movej([0, -1.57, 0, -1.57, 0, 0])
  textmsg(get_freedrive_status())
end''')
    assert not box.errors(), box.errors()
    # at rest, the model is the arm; a believed 2 kg that is not there: the arm carries less than the model says
    assert box.log[:3] == ['True', 'True', '0']
    assert box.log[3:5] == ['True', 'True']  # mid-move: the waypoint is the move's end, the target TCP is on the way
    assert box.log[5] == '2'  # straight up, wrist and elbow aligned: at a singularity


@pytest.mark.parametrize('action', ['pause', 'stop'])
def test_an_rtde_watchdog_pauses_or_stops_the_program_when_its_input_falls_silent(action):
    box = Box()
    writes = []

    def client_writes():  # as the RTDE port records an input package: 100 Hz for 0.2 s, then nothing
        if len(writes) < 20 and len(box.q) % 5 == 0:
            box.robot.rtde_inputs['input_int_register_0'] = box.sim.time
            writes.append(box.sim.time)
    box.before_step = client_writes
    took = box.run(f'''def prog():
  rtde_set_watchdog("input_int_register_0", 50, "{action}")
  while True:
    sync()
  end
end''')
    # the last write at 0.19 s; 20 ms later the watchdog acts, and the program ends within the next cycles (a paused
    # URScript program is not resumed in ur_sim: it ends, as after a dashboard pause)
    assert writes[-1] + 0.02 < took < writes[-1] + 0.03 and box.robot.program_state == STOPPED
    assert box.log[-1].startswith('rtde_set_watchdog: input_int_register_0 was not written for')
    assert box.log[-1].endswith(f'action {action}')


def test_an_rtde_watchdog_refuses_an_unknown_action():
    box = Box()
    box.run('def prog():\n  rtde_set_watchdog("input_int_register_0", 10, "explode")\nend')
    assert 'action is one of ignore, pause, stop' in box.errors()[0].text


def test_direct_torque_on_top_of_gravity_compensation_and_the_servo_back_when_it_stops():
    box = Box()
    box.run('''def prog():
  k = 0
  while k < 250:
    direct_torque([0, 0, 0, 0, 0, 0])
    k = k + 1
  end
  textmsg(norm(get_actual_joint_speeds()) < 1e-3)
  k = 0
  while k < 100:
    direct_torque([0, 0, 0, 0, 0, 0.5])
    k = k + 1
  end
  textmsg(get_actual_joint_speeds()[5] > 1)
  sleep(1.0)
  textmsg(norm(get_actual_joint_speeds()) < 1e-6)
end''')
    assert not box.errors(), box.errors()
    q = np.array(box.q)
    assert np.abs(q[249] - READY).max() < 1e-3  # zero torques: the robot holds the arm up (half a second of gravity)
    assert box.log == ['True', 'True', 'True']
    # after torque control the servo stops the arm as hard as the robot brakes, and holds it there
    assert np.abs(q[-1] - q[-100]).max() < 1e-6 and abs(q[-1][5] - q[350][5]) < 0.6


def test_tcp_force_joint_positions_and_interpolate_pose():
    box = Box()
    box.run('''def prog():
  textmsg(get_joint_positions() == get_actual_joint_positions())
  textmsg(interpolate_pose(p[0, 0, 0, 0, 0, 0], p[0.2, 0, -0.4, 0, 0, 1.0], 0.25))
  textmsg(interpolate_pose(p[0.1, 0, 0, 0, 0, 0.5], p[0.3, 0, 0, 0, 0, -0.5], 1.0))
  ft_rtde_input_enable(True, 0.2, [0, 0, 0.05], [0, 0, 0.02])
  textmsg(get_tcp_force())
end''')
    box.sim.external_ft_input = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert not box.errors(), box.errors()
    assert box.log[0] == 'True'
    assert np.allclose(_values(box.log[1]), [0.05, 0.0, -0.1, 0.0, 0.0, 0.25], atol=1e-6)
    assert np.allclose(_values(box.log[2]), [0.3, 0.0, 0.0, 0.0, 0.0, -0.5], atol=1e-6)
    # The external sensor reads nothing yet; no payload is believed: the TCP force is zero in every axis.
    assert np.allclose(_values(box.log[3]), 0.0, atol=1e-9)


def test_the_external_sensors_reading_is_the_robots_in_base_axes_about_the_tcp():
    box = Box()
    box.run('''def prog():
  ft_rtde_input_enable(True, sensor_measuring_offset=[0, 0, 0.1])
end''')
    box.sim.external_ft_input = np.array([2.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # 2 N along tool0's x, 10 cm out
    flange = box.sim.wrench()
    assert np.allclose(flange, [2.0, 0.0, 0.0, 0.0, 0.2, 0.0])  # about the flange: 0.1 m x 2 N about y
    rot = Rotation.from_quat(box.sim.physics.tcp_pose()[1]).as_matrix()
    assert np.allclose(box.sim.tcp_force(), np.concatenate((rot @ flange[:3], rot @ flange[3:])))
    box.sim.zero_ftsensor()  # the zero is taken off the external reading too
    assert np.allclose(box.sim.wrench(), 0.0)
    box.run('def prog():\n  ft_rtde_input_enable(True, sensor_cog=[0, 0, 6])\nend')
    (error,) = box.errors()
    assert 'ft_rtde_input_enable: sensor_cog = [0.0, 0.0, 6.0] is more than 5.0 m from the flange' in error.text
    assert box.sim.external_ft is not None  # the earlier setting stays
