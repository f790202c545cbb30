"""ur_rtde's control script run natively (``urscript/rtde_control.py``), driven through the registers as
``RTDEControlInterface`` drives it, on the simulated robot stepped cycle by cycle (no ROS, no sockets): the
handshake, each command's motion, asynchronous moves and their progress word, streamed commands, the register offset,
moveUntilContact on the floor, and what it refuses."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from script_box import READY, Box

from ur_sim_driver.robot.robot_state import PLAYING, STOPPED
from ur_sim_driver.urscript import rtde_control as rc
from ur_sim_driver.urscript.runner import RUNTIME_ERROR
from ur_sim_driver.urscript.values import Pose

pytestmark = pytest.mark.timeout(120)


def signed_script(offset: int = 0) -> str:
    """A program with the control script's signature (its first line, section markers and the offsets ur_rtde
    injects after them); the body between is ur_sim's business, not the script's."""
    return (f'def rtde_control():\n# HEADER_BEGIN\n    global reg_offset_float = # float register offset\n{offset}'
            f'    global reg_offset_int = # int register offset\n{offset}\n# HEADER_END\n'
            '# NODE_CONTROL_LOOP_BEGINS\n    textmsg("RTDE Control Script Loaded (ur_sim test)")\n'
            '# NODE_CONTROL_LOOP_ENDS\nend\n')


class Client:
    """The client side of the register protocol, as RTDEControlInterface uses it."""

    def __init__(self, box: Box, offset: int = 0) -> None:
        self.box, self.off = box, offset
        self.regs = box.robot.registers
        box.runner.submit(signed_script(offset))
        box.step()

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
        assert self.state == rc.READY
        self.send(cmd, doubles, ints)
        took = self.until(lambda: self.state == rc.DONE, limit, f'command {cmd} done')
        self.send(0)
        self.until(lambda: self.state == rc.READY, 0.1, 'ready again')
        return took


def _q(box: Box) -> np.ndarray:
    return box.sim.state().q


def test_only_the_signed_script_is_recognised():
    assert rc.recognises(signed_script())
    assert not rc.recognises('def rtde_control():\n  textmsg("mine")\nend\n')  # the name alone is not enough
    assert not rc.recognises('# HEADER_BEGIN\n' + signed_script())  # it must begin the program


def test_ready_then_movej_done_only_at_the_target_and_ready_after_the_clear():
    box = Box()
    client = Client(box)
    assert client.state == rc.READY and box.robot.program_state == PLAYING and box.robot.script == 'rtde_control'
    assert any('natively' in e.text for e in box.events)
    target = np.add(READY, [0.4, -0.2, 0.3, 0.0, 0.2, -0.5])
    took = client.command(1, [*target, 1.0, 2.0], [0])  # v 1 rad/s, a 2 rad/s^2
    # the largest joint step 0.5 rad: a trapezoid of 0.5 / 1 + 1 / 2 = 1 s
    assert took == pytest.approx(1.0, abs=0.01)
    assert np.allclose(_q(box), target, atol=2e-3)


def test_movel_follows_a_line_and_movej_ik_and_movel_fk_reach_their_targets():
    box = Box()
    client = Client(box)
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


def test_an_asynchronous_move_is_done_at_once_reports_progress_and_stopj_ends_it():
    box = Box()
    client = Client(box)
    assert not client.progress & rc.RUNNING_BIT
    target = np.add(READY, [1.0, 0, 0, 0, 0, 0])
    took = client.command(1, [*target, 0.5, 1.0], [1])
    assert took <= 2 * box.sim.control_dt  # done as soon as it started
    assert client.progress & rc.RUNNING_BIT and client.progress >> 24 == 1  # operation 1 running
    client.until(lambda: not client.progress & rc.RUNNING_BIT, 10.0, 'the move finished')
    assert np.allclose(_q(box), target, atol=2e-3)
    # a second one, stopped half way by a synchronous stopJ
    client.command(1, [*READY, 0.5, 1.0], [1])
    assert client.progress >> 24 == 2
    client.until(lambda: abs(_q(box)[0] - target[0]) > 0.4, 10.0, 'half way')
    client.command(34, [2.0], [0])
    assert not client.progress & rc.RUNNING_BIT
    stopped = _q(box)[0]
    for _ in range(250):
        box.step()
    assert abs(_q(box)[0] - stopped) < 2e-3 and stopped > READY[0] + 0.05  # it stopped short of READY


def test_speedj_streams_until_speed_stop_and_servoj_follows_a_moving_target():
    box = Box()
    client = Client(box)
    client.send(9, [0.2, 0, 0, 0, 0, 0, 1.0, 0.0])  # speedJ: 0.2 rad/s, a 1 rad/s^2, no handshake
    client.until(lambda: box.sim.state().qd[0] > 0.199, 2.0, 'the speed')
    assert client.state == rc.READY  # streamed commands are not answered with done
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


def test_upper_range_registers_and_set_payload():
    box = Box()
    client = Client(box, offset=24)
    assert box.robot.registers.output_ints[0] == 0 and client.state == rc.READY
    client.command(17, [1.5, 0.0, 0.01, 0.05])
    assert box.sim.payload.mass == 1.5 and np.allclose(box.sim.payload.cog, [0.0, 0.01, 0.05])
    client.command(17, [2.0, 0.0, 0.0, 0.0])  # a zero CoG keeps the one set
    assert box.sim.payload.mass == 2.0 and np.allclose(box.sim.payload.cog, [0.0, 0.01, 0.05])


def test_move_until_contact_stops_on_the_floor_and_returns_to_where_it_touched():
    box = Box()
    client = Client(box)
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


def test_stop_script_ends_the_program_and_an_unsupported_command_is_a_runtime_error():
    box = Box()
    client = Client(box)
    client.send(255)
    client.until(lambda: box.runner.current is None, 0.1, 'the program ended')
    assert box.robot.program_state == STOPPED and any(e.text == 'Received stop script!' for e in box.events)

    box = Box()
    client = Client(box)
    q0 = _q(box).copy()
    client.send(6, [0.0] * 18, [2, 0, 0, 1, 0, 0, 0])  # forceMode
    client.until(lambda: box.runner.current is None, 0.1, 'the program stopped')
    error = next(e for e in box.events if e.kind == RUNTIME_ERROR)
    assert 'ur_rtde command 6 (FORCE_MODE) is not run by ur_sim' in error.text and 'MOVE_UNTIL_CONTACT' in error.text
    assert client.state == rc.READY  # never done: the client sees runtime_state leave PLAYING
    for _ in range(100):
        box.step()
    assert np.allclose(_q(box), q0, atol=1e-4)  # the arm holds
