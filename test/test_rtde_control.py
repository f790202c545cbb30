"""ur_rtde's own control script, as RTDEControlInterface uploads it, run by ur_sim's URScript interpreter as any
program (there is no recogniser): driven through the registers as the client drives it, on the simulated robot
stepped cycle by cycle. The handshake, each command's motion, asynchronous moves and their progress word, streamed
commands, the upper register range, moveUntilContact on the floor, stopScript, a command whose built-in ur_sim
does not run, and a copy with its banner and section comments changed (nothing depends on recognising it).

The script is ur_rtde's, taken from the robot's side when ur_rtde 1.6.5 (a test dependency) connects to a ur_sim
once for this module; the project holds no copy of it. That ur_sim runs PolyScope 5.26.0: ur_rtde leaves out the
lines of its script that need a newer controller than the one it meets, and its directTorque lines need 5.26 (on
ur_sim's default, 5.25.1, the command loops without sync and the robot stops it, as such a robot would)."""
from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from script_box import READY, Box
from sim_harness import running_sim, wait_still

from ur_sim_driver.robot.robot_state import PLAYING, PROTECTIVE_STOP, STOPPED
from ur_sim_driver.urscript.runner import RUNTIME_ERROR, STARTED
from ur_sim_driver.urscript.values import Pose

pytestmark = pytest.mark.timeout(120)

VERSION = '5.26.0'  # the controller's software: the first for which ur_rtde 1.6.5 sends its direct_torque lines
READY_STATE, DONE = 1, 2  # output_int_register_0: ready for a command, done with it
RUNNING_BIT = 1 << 15  # output_int_register_2: an asynchronous operation runs
_CONNECT = """
import sys, rtde_control
control = rtde_control.RTDEControlInterface(sys.argv[1])
control.stopScript()
control.disconnect()
"""


@pytest.fixture(scope='module')
def script() -> str:
    """The control script ur_rtde uploads with its default flags (registers 0-23)."""
    address = f'127.0.0.{10 + int(os.environ.get("ROS_DOMAIN_ID", "0")) % 240}'
    ports = {'dashboard_server': 29999, 'rtde': 30004, 'primary': 30001, 'secondary': 30002, 'realtime': 30003}
    sources = []
    endpoints = {name: {'host': address, 'port': port} for name, port in ports.items()}
    with running_sim(paced=True, software_version=VERSION, **endpoints) as h:
        runner = h.sim.host.scripts

        def keep(event):
            if event.kind == STARTED and runner.current is not None:
                sources.append(runner.current.source)
        undo = runner.listen(keep)
        try:
            done = subprocess.run([sys.executable, '-c', _CONNECT, address], capture_output=True, text=True,
                                  timeout=60)
            assert done.returncode == 0, done.stderr[-3000:]
            wait_still(lambda: runner.current is None, what='the control script ended')
        finally:
            undo()
    (source,) = sources
    assert source.startswith('def rtde_control():')
    return source


def upper_range(source: str) -> str:
    """The script as ur_rtde makes it with FLAG_UPPER_RANGE_REGISTERS: the register offsets 24."""
    return re.sub(r'(# (?:float|int) register offset\s*)0', r'\g<1>24', source)


class Client:
    """The client side of the register protocol, as RTDEControlInterface uses it."""

    def __init__(self, box: Box, source: str, offset: int = 0) -> None:
        self.box, self.off = box, offset
        self.regs = box.robot.registers
        box.runner.submit(source)
        self.until(lambda: self.state == READY_STATE, 0.1, 'the script ready')

    @property
    def state(self) -> int:
        return self.regs.output_ints[self.off]

    @property
    def progress(self) -> int:
        return self.regs.output_ints[self.off + 2]

    def send(self, cmd: int, doubles=(), ints=()) -> None:
        for k, v in enumerate(doubles):
            self.regs.input_doubles[self.off + k] = float(v)
        for k, v in enumerate(ints, start=1):
            self.regs.input_ints[self.off + k] = int(v)
        self.regs.input_ints[self.off] = cmd

    def until(self, condition, limit: float = 20.0, what: str = 'condition') -> float:
        """Step until `condition()`; the simulated time it took [s]."""
        t0 = self.box.sim.time
        while not condition():
            assert self.box.sim.time - t0 < limit, f'{what}: not within {limit} s of simulated time'
            self.box.step()
        return self.box.sim.time - t0

    def command(self, cmd: int, doubles=(), ints=(), limit: float = 20.0) -> float:
        """Send, wait for done, clear, wait for ready (the client's sendCommand); the time to done [s]."""
        assert self.state == READY_STATE
        self.send(cmd, doubles, ints)
        took = self.until(lambda: self.state == DONE, limit, f'command {cmd} done')
        self.send(0)
        self.until(lambda: self.state == READY_STATE, 0.1, 'ready again')
        return took


def _q(box: Box) -> np.ndarray:
    return box.sim.state().q


def test_ready_then_movej_done_only_at_the_target_and_ready_after_the_clear(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    assert client.state == READY_STATE and box.robot.program_state == PLAYING and box.robot.script == 'rtde_control'
    assert box.log[0].startswith('RTDE Control Script Loaded')
    target = np.add(READY, [0.4, -0.2, 0.3, 0.0, 0.2, -0.5])
    took = client.command(1, [*target, 1.0, 2.0], [0])  # v 1 rad/s, a 2 rad/s^2
    # the largest joint step 0.5 rad: a trapezoid of 0.5 / 1 + 1 / 2 = 1 s
    assert took == pytest.approx(1.0, abs=0.01)
    assert np.allclose(_q(box), target, atol=2e-3)


def test_movel_follows_a_line_and_movej_ik_and_movel_fk_reach_their_targets(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    ik = box.runner.compile('textmsg(1)\n').ik  # the controller's kinematics, base frame
    start = ik.fk(_q(box))
    pose = np.concatenate((start[:3, 3] + [0.0, 0.1, -0.05], Rotation.from_matrix(start[:3, :3]).as_rotvec()))
    n0 = len(box.tcp)
    client.command(3, [*pose, 0.1, 1.0], [0])
    tcp = np.array(box.tcp[n0:])  # the TCP in the physics, base frame
    line = (pose[:3] - start[:3, 3]) / np.linalg.norm(pose[:3] - start[:3, 3])
    off = (tcp - start[:3, 3]) - np.outer((tcp - start[:3, 3]) @ line, line)
    assert np.abs(off).max() < 1e-3 and np.allclose(tcp[-1], pose[:3], atol=1e-3)
    # moveJ_IK: a pose, reached by joint motion; moveL_FK: joints, reached along a line
    back = np.concatenate((start[:3, 3], Rotation.from_matrix(start[:3, :3]).as_rotvec()))
    client.command(2, [*back, 1.0, 2.0], [0])
    assert np.allclose(ik.fk(_q(box))[:3, 3], start[:3, 3], atol=1e-3)
    q_goal = np.add(READY, [0.2, 0.0, 0.0, 0.0, 0.0, 0.0])
    client.command(4, [*q_goal, 0.2, 1.0], [0])
    assert np.allclose(_q(box), q_goal, atol=2e-3)


def test_an_asynchronous_move_is_done_at_once_reports_progress_and_stopj_ends_it(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    assert not client.progress & RUNNING_BIT
    target = np.add(READY, [1.0, 0, 0, 0, 0, 0])
    took = client.command(1, [*target, 0.5, 1.0], [1])
    assert took <= 2 * box.sim.control_dt  # done as soon as it started
    assert client.progress & RUNNING_BIT and client.progress >> 24 == 1  # operation 1 running
    client.until(lambda: not client.progress & RUNNING_BIT, 10.0, 'the move finished')
    assert np.allclose(_q(box), target, atol=2e-3)
    # a second one, stopped half way by a synchronous stopJ
    client.command(1, [*READY, 0.5, 1.0], [1])
    assert client.progress >> 24 == 2
    client.until(lambda: abs(_q(box)[0] - target[0]) > 0.4, 10.0, 'half way')
    client.command(34, [2.0], [0])
    assert not client.progress & RUNNING_BIT
    stopped = _q(box)[0]
    for _ in range(250):
        box.step()
    assert abs(_q(box)[0] - stopped) < 2e-3 and stopped > READY[0] + 0.05  # it stopped short of READY


def test_speedj_streams_until_speed_stop_and_servoj_follows_a_moving_target(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    client.send(9, [0.2, 0, 0, 0, 0, 0, 1.0, 0.0])  # speedJ: 0.2 rad/s, a 1 rad/s^2, no handshake
    client.until(lambda: box.sim.state().qd[0] > 0.199, 2.0, 'the speed')
    assert client.state == READY_STATE  # streamed commands are not answered with done
    for _ in range(100):
        box.step()
    assert box.sim.state().qd[0] == pytest.approx(0.2, abs=2e-3)
    took = client.command(15, [2.0])  # speedStop, a 2 rad/s^2
    assert took == pytest.approx(0.1, abs=0.01) and abs(box.sim.state().qd[0]) < 0.01
    q = _q(box).copy()
    for _ in range(250):  # servoJ at 0.1 rad/s, t = one cycle, lookahead 0.1 s, gain 300
        q[1] += 0.1 * box.sim.control_dt
        client.send(11, [*q, 0.0, 0.0, box.sim.control_dt, 0.1, 300.0])
        box.step()
    assert _q(box)[1] == pytest.approx(q[1], abs=5e-3) and box.sim.state().qd[1] == pytest.approx(0.1, abs=0.02)
    client.command(16, [2.0])  # servoStop: the setpoint stops; the arm, 5 mrad behind it, within 0.1 s
    for _ in range(50):
        box.step()
    assert abs(box.sim.state().qd[1]) < 0.01 and _q(box)[1] == pytest.approx(q[1], abs=2e-3)


def test_upper_range_registers_and_set_payload(script):
    box = Box(software_version=VERSION)
    client = Client(box, upper_range(script), offset=24)
    assert box.robot.registers.output_ints[0] == 0 and client.state == READY_STATE
    client.command(17, [1.5, 0.0, 0.01, 0.05])
    assert box.sim.payload.mass == 1.5 and np.allclose(box.sim.payload.cog, [0.0, 0.01, 0.05])
    client.command(17, [2.0, 0.0, 0.0, 0.0])  # a zero CoG keeps the one set
    assert box.sim.payload.mass == 2.0 and np.allclose(box.sim.payload.cog, [0.0, 0.01, 0.05])


def test_move_until_contact_stops_on_the_floor_and_returns_to_where_it_touched(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    program = box.runner.compile('textmsg(1)\n')  # the controller's kinematics, base frame
    above = program.ik.fk(np.array(READY))  # the tool points down
    above[2, 3] = 0.06  # [m] the flange 6 cm above the floor
    client.command(1, [*program.inverse_kin(Pose.from_matrix(above), list(READY)), 1.0, 2.0], [0])
    took = client.command(51, [0, 0, -0.02, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.5])  # 20 mm/s down, any contact
    assert took == pytest.approx(0.06 / 0.02, abs=0.1)  # the floor is where the flange meets it
    for _ in range(50):
        box.step()
    tcp = program.ik.fk(_q(box))
    assert abs(tcp[2, 3]) < 2e-3 and np.allclose(tcp[:2, 3], above[:2, 3], atol=1e-3)
    assert abs(box.sim.state().qd).max() < 0.01


def test_direct_torque_turns_the_wrist_while_it_is_streamed_and_the_arm_holds_after(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    q0 = _q(box).copy()
    # 1 N m on wrist_3, every cycle (gravity is compensated). ur_rtde's script passes all-zero friction scales, so
    # the joint feels its whole Coulomb friction (0.56 N m on a UR5e's wrist) and the rest turns it.
    client.send(66, [0.0] * 5 + [1.0] + [0.0] * 12)
    for _ in range(25):  # 0.05 s
        box.step()
    qd = box.sim.state().qd
    assert qd[5] > 0.5 and np.all(np.abs(qd[:5]) < 0.05), qd
    assert box.runner.current is not None and not box.errors()
    client.send(255)  # stopScript: the program ends, the robot brakes the arm and holds it
    client.until(lambda: box.runner.current is None, 0.1, 'the program ended')
    for _ in range(500):
        box.step()
    assert np.all(np.abs(box.sim.state().qd) < 1e-3) and _q(box)[5] > q0[5]


def test_the_external_force_torque_sensor_replaces_the_reading_and_disabling_it_restores_the_arms(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    own = box.sim.wrench().copy()
    client.command(56, [0.3, 0.0, 0.0, 0.02, 0.0, 0.0, 0.01], [1])  # 0.3 kg, measuring 2 cm out along z
    box.sim.external_ft_input = np.array([1.0, 0.0, 10.0, 0.0, 0.0, 0.0])  # as RTDE's external_force_torque sets it
    # The measurement is about the measuring point: 1 N along x there turns the flange by 0.02 m x 1 N about y.
    assert np.allclose(box.sim.wrench(), [1.0, 0.0, 10.0, 0.0, 0.02, 0.0], atol=1e-12)
    assert box.sim.external_ft.mass == 0.3 and np.allclose(box.sim.external_ft.cog, [0.0, 0.0, 0.01])
    client.command(56, [0.0] * 7, [0])  # disabled
    assert box.sim.external_ft is None and np.allclose(box.sim.wrench(), own, atol=0.5)


def test_stop_script_ends_the_program_and_an_unsupported_command_is_a_runtime_error(script):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    client.send(255)
    client.until(lambda: box.runner.current is None, 0.1, 'the program ended')
    assert box.robot.program_state == STOPPED and any(e.text == 'Received stop script!' for e in box.events)

    box = Box(software_version=VERSION)
    client = Client(box, script)
    q0 = _q(box).copy()
    client.send(56, [-1.0] + [0.0] * 6, [1])  # ftRtdeInputEnable with a sensor of -1 kg
    client.until(lambda: box.runner.current is None, 0.1, 'the program stopped')
    error = next(e for e in box.events if e.kind == RUNTIME_ERROR)
    assert 'ft_rtde_input_enable: sensor_mass = -1.0 kg is outside [0, 100.0]' in error.text and error.line > 0
    for _ in range(100):
        box.step()
    assert np.allclose(_q(box), q0, atol=1e-4)  # the arm holds
    assert box.sim.external_ft is None


def test_a_copy_with_its_banner_and_section_comments_changed_runs_the_same(script):
    custom = re.sub(r'#[^\n]*', '# ours', script).replace('RTDE Control Script Loaded', 'Our control script')
    custom = custom.replace('def rtde_control():', 'def our_control():', 1)
    assert 'HEADER_BEGIN' not in custom and 'NODE_CONTROL_LOOP' not in custom
    box = Box(software_version=VERSION)
    client = Client(box, custom)
    assert box.robot.script == 'our_control' and box.log[0].startswith('Our control script')
    target = np.add(READY, [0.3, 0.0, 0.0, 0.0, 0.0, 0.0])
    client.command(1, [*target, 1.0, 2.0], [0])
    assert np.allclose(_q(box), target, atol=2e-3)


# ur_rtde 1.6.5's command numbers (RobotCommand::Type): all 70 run (docs/ports.md).
RUNS = (1, 2, 3, 4, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30,
        31, 33, 34, 35, 36, 37, 38, 39, 40, 41, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59,
        60, 61, 62, 63, 64, 65, 66, 67, 68, 69, 70, 71, 255)
JOINT_ARGUMENTS = (1, 4, 9, 11, 27, 37, 44, 60, 61)  # the first six doubles are joints (else a pose or a speed)


def _arguments(box: Box, cmd: int) -> tuple[list[float], list[int]]:
    """Plausible arguments: a small step from READY (joints or the TCP pose), v 0.5, a 1, t one cycle, lookahead
    0.1, gain 300; then what a few commands need instead."""
    q = [float(v) for v in np.add(READY, [0.05, 0.0, 0.0, 0.0, 0.0, 0.0])]
    pose = list(box.runner.compile('textmsg(1)\n').forward_kin(np.array(READY), None).values)
    doubles = (q if cmd in JOINT_ARGUMENTS else pose) + [0.5, 1.0, 0.002, 0.1, 300.0] + [0.0] * 37
    ints = [0] * 7
    if cmd in (9, 10):  # speedJ, speedL: a small speed, a 1, no time
        doubles[:8] = [0.01, 0, 0, 0, 0, 0, 1.0, 0.0]
    elif cmd == 35:  # setWatchdog at 1 Hz: nothing writes the register here, and 0.2 s is within its second
        doubles[0] = 1.0
    elif cmd in (15, 16, 33, 34):  # the stops: a deceleration
        doubles[0] = 2.0
    elif cmd in (17, 65):  # the payload: 1 kg, 5 cm out along the flange, no inertia of its own
        doubles[:10] = [1.0, 0.0, 0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    elif cmd in (20, 21):  # force mode's damping and gain scaling
        doubles[0] = 0.5
    elif cmd == 41:  # jog in the base feature
        doubles[:8] = [0.01, 0, 0, 0, 0, 0, 0.0, 0.5]
    elif cmd == 51:  # moveUntilContact: 10 mm/s down
        doubles[:13] = [0, 0, -0.01, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.5]
    elif cmd == 52:  # freedrive, every axis free
        ints = [1] * 7
    elif cmd in (56, 57):  # the external force-torque sensor: 0.3 kg, measuring 2 cm out, its centre 1 cm out
        doubles[:7] = [0.3, 0.0, 0.0, 0.02, 0.0, 0.0, 0.01]
        ints = [0, 1]  # enable
    elif cmd == 66:  # directTorque: 0.2 N m on wrist_3, no friction scales
        doubles[:18] = [0.0] * 5 + [0.2] + [0.0] * 12
    elif cmd == 6:  # forceMode: the base frame, 5 N up along z, its speed and the other axes' deviation limits
        doubles[:18] = [0.0] * 6 + [0.0, 0.0, 5.0, 0.0, 0.0, 0.0] + [0.1] * 6
        ints = [0, 2, 0, 0, 1, 0, 0, 0]  # type 2, then the selection vector
    return doubles, ints


@pytest.mark.parametrize('cmd', RUNS)
def test_each_command_runs(script, cmd):
    box = Box(software_version=VERSION)
    client = Client(box, script)
    doubles, ints = _arguments(box, cmd)
    client.send(cmd, doubles, ints[1:])
    for _ in range(100):  # 0.2 s: every command has been taken and answered (or has failed) by then
        box.step()
        if box.runner.current is None:
            break
    errors = [e.text for e in box.events if e.kind == RUNTIME_ERROR]
    if cmd == 255:
        assert not errors and box.runner.current is None  # stopScript ends it
    elif cmd == 31:
        assert not errors and box.runner.current is None  # triggerProtectiveStop: the robot stops the program
        assert box.robot.safety_mode == PROTECTIVE_STOP
    else:
        assert not errors and box.runner.current is not None, errors
