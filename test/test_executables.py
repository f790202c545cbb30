"""The installed executables, found the way `ros2 run` finds them, run and stop cleanly on signals."""
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from action_msgs.msg import GoalStatus
from ament_index_python.packages import get_package_prefix, get_resource
from rclpy.node import Node
from ros_helpers import executor_with, ros_context, spin_until
from sensor_msgs.msg import JointState


def _executable(name: str) -> Path:
    # `ros2 run PKG EXE` looks for an executable <prefix>/lib/PKG/EXE of the package found in the ament index.
    get_resource('packages', 'ur_sim_driver')
    path = Path(get_package_prefix('ur_sim_driver')) / 'lib' / 'ur_sim_driver' / name
    assert path.is_file() and os.access(path, os.X_OK), f'{path} is not an executable'
    return path


def _start_ur_sim(**popen) -> subprocess.Popen:
    return subprocess.Popen([str(_executable('ur_sim')), '--ros-args', '-p', 'real_time_factor:=0.0'],
                            start_new_session=True, **popen)


def _joint_states(count: int) -> list:
    """Wait for `count` /joint_states messages from the ur_sim process."""
    received = []
    with ros_context() as ctx:
        node = Node('exe_probe', context=ctx)
        node.create_subscription(JointState, '/joint_states', received.append, 10)
        with executor_with(ctx, node) as ex:
            spin_until(ex, lambda: len(received) >= count, 30.0, '/joint_states from the ur_sim process')
    return received


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_ur_sim_publishes_joint_states_and_exits_cleanly_on_signal(sig):
    proc = _start_ur_sim(stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        received = _joint_states(5)
    finally:
        os.killpg(proc.pid, sig)
        try:
            out, _ = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise
    assert proc.returncode == 0, out
    assert 'Traceback' not in out
    assert list(received[-1].name) == ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
                                       'wrist_2_joint', 'wrist_3_joint']
    assert len(received[-1].effort) == 6


def test_a_goal_running_when_ur_sim_stops_ends_aborted_and_the_process_exits():
    # The controllers' process answers a goal still running at the stop (its client is not left waiting), then
    # ends without waiting out a fixed time.
    from control_msgs.action import FollowJointTrajectory
    from rclpy.action import ActionClient
    from trajectory_msgs.msg import JointTrajectoryPoint

    from ur_sim_driver.description.params import joint_names
    from ur_sim_driver.motion.conversions import sec_to_duration

    proc = _start_ur_sim(stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        with ros_context() as ctx:
            node = Node('exe_goal_probe', context=ctx)
            client = ActionClient(node, FollowJointTrajectory,
                                  '/scaled_joint_trajectory_controller/follow_joint_trajectory')
            with executor_with(ctx, node) as ex:
                spin_until(ex, client.server_is_ready, 30.0, 'the trajectory action server')
                goal = FollowJointTrajectory.Goal()
                goal.trajectory.joint_names = joint_names()
                # 1000 s of robot time: still running whatever the machine's speed
                goal.trajectory.points = [JointTrajectoryPoint(positions=[0.1, -1.57, 0.0, -1.57, 0.0, 0.0],
                                                               time_from_start=sec_to_duration(1000.0))]
                sent = client.send_goal_async(goal)
                spin_until(ex, sent.done, 30.0, 'the goal answer')
                assert sent.result().accepted
                result = sent.result().get_result_async()
                os.killpg(proc.pid, signal.SIGINT)
                spin_until(ex, result.done, 30.0, 'the result of the goal running at the stop')
        out, _ = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert result.result().status == GoalStatus.STATUS_ABORTED
    assert result.result().result.error_string == 'ur_sim is shutting down.'
    assert proc.returncode == 0, out


def test_ur_glue_planner_executable_is_installed():
    _executable('ur_glue_planner')


def test_timestamps_are_simulated_time():
    proc = _start_ur_sim(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        received = _joint_states(2)
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=20)
    stamp = received[-1].header.stamp
    # Simulated time starts at 0; a wall-clock stamp would be ~1.7e9 s.
    assert 0 < stamp.sec + stamp.nanosec * 1e-9 < time.time() / 1000


@pytest.mark.parametrize('job', ['config/glue_job.yaml', ''])
def test_ur_glue_studio_serves_the_page_and_exits_cleanly(job):
    # With a job: the studio; without: the live viewer. Both serve viser's page and stop on SIGINT.
    import socket
    import urllib.request
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        port = s.getsockname()[1]
    args = [str(_executable('ur_glue_studio')), '--ros-args', '-p', f'port:={port}']
    if job:
        args += ['-p', f'job:={Path(__file__).resolve().parents[1] / job}']
    proc = subprocess.Popen(args, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60.0
        while True:
            try:
                page = urllib.request.urlopen(f'http://127.0.0.1:{port}', timeout=2).read().decode()
                break
            except OSError:
                assert proc.poll() is None and time.monotonic() < deadline, 'the studio did not serve its page'
                time.sleep(0.2)
        assert '<div id="root">' in page
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise
    assert proc.returncode == 0, out
    assert f'http://127.0.0.1:{port}' in out and 'Traceback' not in out
    assert ('job ' if job else 'live viewer') in out


def test_ur_glue_studio_rejects_a_bad_parameter():
    proc = subprocess.run([str(_executable('ur_glue_studio')), '--ros-args', '-p', 'port:=99999'],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert 'port: 99999 is not an integer in [1, 65535]' in proc.stderr
