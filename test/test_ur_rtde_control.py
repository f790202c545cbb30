"""ur_rtde (PyPI ur-rtde) as its users run it, against ur_sim's ports: RTDEControlInterface with its default flags
uploads its control script on the real-time port and drives the robot through RTDE registers; ur_sim's URScript
interpreter runs the script as it runs any program (threads included). On a loopback address of this test
process's own (ur_rtde has no port arguments; ROS_DOMAIN_ID is unique per process), paced to the wall clock that
ur_rtde waits on."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from sim_harness import running_sim, wait_still

from ur_sim_driver.robot.robot_state import STOPPED

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope='module')
def run():
    address = f'127.0.0.{10 + int(os.environ.get("ROS_DOMAIN_ID", "0")) % 240}'
    ports = {'dashboard_server': 29999, 'rtde': 30004, 'primary': 30001, 'secondary': 30002, 'realtime': 30003}
    with running_sim(paced=True, **{name: {'host': address, 'port': port} for name, port in ports.items()}) as h:
        done = subprocess.run([sys.executable, str(Path(__file__).with_name('ur_rtde_control_client.py')), address],
                              capture_output=True, text=True, timeout=240)
        assert done.returncode == 0, done.stderr[-3000:]
        out = json.loads(done.stdout.strip().splitlines()[-1])
        wait_still(lambda: h.sim.host.scripts.current is None, what='the control script ended')
        with h.sim.host.lock:
            final = h.sim.sim.state().q.copy(), h.sim.host.robot.program_state
        yield out, final


def test_the_dashboard_client_starts_the_robot_and_the_io_interface_sets_the_slider(run):
    out, _ = run
    assert out['power_off'] and out['running_mode']
    assert out['loaded'] == 'Loaded program: /programs/wait_program.urp' and out['playing']
    assert out['slider'] and out['slider_read'] == pytest.approx(0.5)


def test_it_connects_and_each_move_reaches_its_target(run):
    out, _ = run
    assert out['connected'] and out['running']
    assert out['movej'] and np.allclose(out['movej_q'], [0.0, -1.2, 1.2, -1.57, -1.57, 0.0], atol=2e-3)
    assert out['movel'] and np.allclose(out['movel_pose'][:3], out['movel_target'][:3], atol=1e-3)


def test_streamed_speed_and_servo_commands_and_their_stops(run):
    out, _ = run
    assert out['speedj'] and out['speedj_fastest'] == pytest.approx(0.2, abs=0.01) and out['speed_stop']
    assert out['servoj'] and out['servo_stop']
    assert out['servoj_q'][1] == pytest.approx(out['servoj_target'][1], abs=2e-3)


def test_an_asynchronous_move_runs_until_stopj(run):
    out, _ = run
    assert out['movej_async'] and out['async_running']
    assert out['async_after_stop'] < 0  # finished: stopped
    start = out['async_far'][0] - 1.0
    assert start + 0.05 < out['stopj_q'][0] < out['async_far'][0] - 0.05  # it stopped part way


def test_move_until_contact_stops_where_the_flange_meets_the_floor(run):
    out, _ = run
    assert out['movel_down'] and out['contact']
    assert abs(out['contact_pose'][2]) < 3e-3


def test_stop_script_ends_the_program_and_the_arm_holds(run):
    out, (q, program_state) = run
    assert not out['running_after_stop'] and program_state == STOPPED
    assert np.allclose(q, out['q_final'], atol=1e-3)
