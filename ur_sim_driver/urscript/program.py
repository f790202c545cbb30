"""A URScript program running on the simulated robot: the robot's commander while it plays, stepped by the
simulation loop under its lock, one control period at a time.

Each cycle: the time of the cycle that passed is counted (a move's time at the speed scaling factor, as the
robot's speed slider and its own slowing scale every motion; ``sleep`` in robot time), the program's threads run
on until each waits again (``threads.py``), and the current move is sampled for the robot's servo (the last motion
commanded by any thread wins), which keeps the joints within their limits as
it does for ROS controllers. A runtime error stops the program where it is; the arm holds. A program that ends while
a ``speedj`` still moves the arm stops it (``stopj`` at :data:`END_DECELERATION`).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ur_sim_driver.description.analytic_ik import UrAnalyticIK, nearest_branch
from ur_sim_driver.errors import ConfigError, ScriptError
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.physics.tool_contact import strongest_touch
from ur_sim_driver.robot.robot_state import RobotState
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.urscript.grammar import parse
from ur_sim_driver.urscript.interpreter import Interpreter
from ur_sim_driver.urscript.moves import JointLine, Move, Servo, Speed, ToolLine, ToolSpeed, tool_jacobian
from ur_sim_driver.urscript.rtde_control import RtdeControlLoop, recognises
from ur_sim_driver.urscript.values import Pose, Request, is_number, show

END_DECELERATION = 2.0  # [rad/s^2] a program that ends while the arm moves at speed stops it with this
_DH_FROM_BASE_LINK = np.diag([-1.0, -1.0, 1.0, 1.0])  # the controller's base frame is DH frame 0


class ScriptProgram:
    """One program (parsed at construction: a syntax error raises ScriptError and nothing runs).

    Args:
        source: the URScript text.
        sim, robot: the simulated robot (read and changed under the simulation lock).
        factor: the robot's speed scaling factor now, in [0, 1].
        log: where textmsg writes (the robot's log).
        name: the program's name when it defines none (bare statements).
        sockets: its client connections (``ports.script_sockets.ScriptSockets``), closed when it ends; None: a
            program without network (a socket function is then a runtime error).
    """

    def __init__(self, source: str, sim: Simulator, robot: RobotState, factor: Callable[[], float],
                 log: Callable[[str], None], name: str = 'unnamed', sockets=None) -> None:
        # ur_rtde's control script runs as a native loop of the same requests (rtde_control.py)
        self.interpreter = RtdeControlLoop(source, self) if recognises(source) else Interpreter(parse(source), self)
        self.name = self.interpreter.name or name
        self.secondary = self.interpreter.secondary
        self.sim, self.robot, self._factor, self._log = sim, robot, factor, log
        self._sockets = sockets
        self.ik = UrAnalyticIK(sim.params.dh, base_pose=_DH_FROM_BASE_LINK)
        self.error: ScriptError | None = None
        self.finished = False  # the program has ended (and the arm was commanded to rest)
        self.threads = self.interpreter.threads
        self._program_done = False
        self._move: Move | None = None
        self._move_t = 0.0  # [s] of the current move's own (scaled) time
        self._ref: TrajectorySample | None = None
        self._qd_nominal: np.ndarray | None = None  # the current move's velocity this cycle [rad/s]

    # ---- the commander ------------------------------------------------------------------------------------
    def take_over(self, state: ArmState) -> None:
        zero = np.zeros_like(state.q)
        self._ref = TrajectorySample(state.q.copy(), zero, zero.copy(), 0, True)

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        if self._ref is None:
            self.take_over(state)
        factor = self._factor()
        current = self._move
        if current is not None:  # where the current move is now: a move the program starts this cycle starts there
            self._move_t += period * factor
            self._sample(factor)
        self.threads.new_cycle(period)
        if self._sockets is not None:
            self._sockets.flush()
        self._run()
        if self._move is None:
            return self._ref, self._ref.positions
        if self._move is not current:  # started this cycle: its first sample
            self._sample(factor)
        ended = self._ref.ended
        if ended and self._program_done:
            self.finished = True
        return self._ref, (self._ref.positions if ended else None)

    def _sample(self, factor: float) -> None:
        """The reference from the current move at its time; its nominal (unscaled) velocity kept for the next."""
        q, qd, qdd = self._move.sample(self._move_t)
        self._qd_nominal = qd
        self._ref = TrajectorySample(q, qd * factor, qdd * factor * factor, 0, self._move_t >= self._move.duration)

    def torques(self) -> None:
        """A program moves the arm through the robot's servo (ur_sim's URScript has no direct_torque)."""
        return None

    def halt(self, q: np.ndarray, reason: str) -> None:
        self._stop(ScriptError(f'the robot halted the program: {reason}'), q)

    def run_now(self) -> None:
        """Run a secondary program to its end at once (it cannot wait for robot time); its runtime error, if
        any, is in `error`."""
        self._run()

    # ---- the program --------------------------------------------------------------------------------------
    def _run(self) -> None:
        if self._program_done:
            return
        try:
            self.threads.step(self._handle)
        except ScriptError as exc:
            self._stop(exc, None)
            return
        except ConfigError as exc:  # a move the robot refuses: the statement that asked, its line
            thread = self.threads.current or self.threads.main
            self._stop(ScriptError(f'line {thread.line}: {exc}', thread.line, thread.column), None)
            return
        if self.threads.main.done or self.threads.halted:
            self._end()

    def _handle(self, thread, request: Request):
        """A thread's motion: the arm's move from now on; the thread waits until the move returns (or another
        replaces it)."""
        try:
            move = self._build(*request.args)
        except ScriptError as exc:  # the statement that asked: its line
            if exc.line:
                raise
            raise ScriptError(f'line {thread.line}: {exc}', thread.line, thread.column) from None
        self._move = move
        self._move_t = 0.0
        self._qd_nominal = move.sample(0.0)[1]  # a move built next in this same cycle starts from it
        # 'move' returns when the motion function would; 'start' (a native loop's) at once
        if request.kind != 'move' or move.returns_after <= 0.0:
            return None
        return lambda: self._move is not move or self._move_t >= move.returns_after

    def _end(self) -> None:
        self._program_done = True
        if self._move is not None and np.isinf(self._move.duration):  # still at speed: stop the arm
            self._move = Speed(self._ref.positions, self._nominal_qd(), np.zeros(len(self._ref.positions)),
                               END_DECELERATION, None)
            self._move_t = 0.0
        elif self._move is None or self._move_t >= self._move.duration:
            self.finished = True

    def _stop(self, error: ScriptError, q: np.ndarray | None) -> None:
        """A runtime error (or the robot's halt): the program ends here and the arm holds where it is commanded."""
        self.error = error
        self._program_done = True
        self.finished = True
        hold = self._ref.positions if q is None and self._ref is not None else q
        if hold is not None:
            zero = np.zeros_like(hold)
            self._ref = TrajectorySample(np.array(hold, float), zero, zero.copy(), 0, True)
        self._move = None

    def _nominal_qd(self) -> np.ndarray:
        """(n,) the current move's velocity this cycle [rad/s], before speed scaling (sampled once per cycle)."""
        if self._move is None:
            return np.zeros(len(self._ref.positions))
        return self._qd_nominal

    # ---- moves --------------------------------------------------------------------------------------------
    def _build(self, kind: str, *args) -> Move:
        q0 = self._ref.positions.copy()
        p = self.sim.params
        if kind == 'movej':
            target, a, v, t, _r = args
            q1 = self._joints(kind, target, q0)
            return JointLine(q0, q1, _positive(f'{kind}: a', a), _positive(f'{kind}: v', v), _time(kind, t))
        if kind == 'movel':
            target, a, v, t, _r = args
            t1 = target.matrix() if isinstance(target, Pose) else self.ik.fk(_joints6(kind, target))
            return ToolLine(self.ik, q0, self.ik.fk(q0), t1, _positive(f'{kind}: a', a), _positive(f'{kind}: v', v),
                            _time(kind, t), self.sim.control_dt, p.q_min, p.q_max)
        if kind == 'speedj':
            qd, a, t = args
            qd = np.array(_joints6(f'{kind}: qd', qd))
            over = np.flatnonzero(np.abs(qd) > p.v_max)
            if over.size:
                j = int(over[0])
                raise ScriptError(f'speedj: qd[{j}] = {qd[j]:g} rad/s is over the joint speed limit {p.v_max[j]:g}')
            return Speed(q0, self._nominal_qd(), qd, _positive(f'{kind}: a', a), None if t is None else _time(kind, t))
        if kind == 'stopj':
            (a,) = args
            return Speed(q0, self._nominal_qd(), np.zeros(len(q0)), _positive(f'{kind}: a', a), None)
        if kind == 'speedl':
            xd, a, t, a_rot = args
            return ToolSpeed(self.ik, q0, self._tool_twist(), np.array(_joints6(f'{kind}: xd', xd)),
                             _positive(f'{kind}: a', a), _positive(f'{kind}: aRot', a if a_rot is None else a_rot),
                             None if t is None else _time(kind, t), self.sim.control_dt)
        if kind == 'stopl':
            a, a_rot = args
            return ToolSpeed(self.ik, q0, self._tool_twist(), np.zeros(6), _positive(f'{kind}: a', a),
                             _positive(f'{kind}: aRot', a if a_rot is None else a_rot), None, self.sim.control_dt)
        if kind == 'servoj':
            target, _a, _v, t, _lookahead, _gain = args
            return Servo(q0, self._joints(kind, target, q0), _positive(f'{kind}: t', t))
        raise ScriptError(f'{kind} is not supported by ur_sim')

    def _tool_twist(self) -> np.ndarray:
        """(6,) the tool's nominal twist now (linear [m/s], angular [rad/s]; base axes)."""
        return tool_jacobian(self.ik, self._ref.positions) @ self._nominal_qd()

    def _joints(self, kind: str, target, q_near: np.ndarray) -> np.ndarray:
        """Joint positions of a move's target (a pose: by IK, the solution nearest `q_near`), within the limits."""
        q = np.array(self.inverse_kin(target, list(q_near))) if isinstance(target, Pose) else \
            np.array(_joints6(f'{kind}: q', target))
        p = self.sim.params
        outside = np.flatnonzero((q < p.q_min) | (q > p.q_max))
        if outside.size:
            j = int(outside[0])
            raise ScriptError(f'{kind}: target joint {j} = {q[j]:.4f} rad is outside its limits '
                              f'[{p.q_min[j]:.4f}, {p.q_max[j]:.4f}]')
        return q

    # ---- ScriptRobot: what the program reads and sets -------------------------------------------------------
    def joint_positions(self) -> list[float]:
        return [float(v) for v in self.sim.state().q]

    def tcp_pose(self) -> Pose:
        return Pose.from_matrix(self.ik.fk(self.sim.state().q))

    def inverse_kin(self, pose: Pose, qnear: list[float] | None) -> list[float]:
        near = np.array(qnear if qnear is not None else self.sim.state().q, float)
        solutions = self.ik.solve(pose.matrix())
        if not np.any(np.all(np.isfinite(solutions), axis=1)):
            raise ScriptError(f'get_inverse_kin: {pose} is out of reach')
        branch, _ = nearest_branch(solutions, near)
        q = solutions[branch]
        q = near + (q - near + np.pi) % (2.0 * np.pi) - np.pi  # each joint's turn nearest qnear
        return [float(v) for v in q]

    def move_finished(self) -> bool:
        """No move runs, or the current one has reached its end."""
        return self._move is None or self._move_t >= self._move.duration

    def tool_touch(self) -> bool:
        """The tool or the flange touches something over the tool contact force, this control period."""
        return strongest_touch(self.sim.physics.contacts(), self.sim.tool_bodies, self.sim.tool_contact_force) \
            is not None

    def payload_cog(self) -> list[float]:
        """The payload's centre of gravity the robot believes in (tool0 [m])."""
        return [float(v) for v in self.sim.payload.cog]

    def set_digital_out(self, pin: int, on: bool) -> None:
        self.sim.io = self.sim.io.with_digital_out(pin, float(on))

    def digital_out(self, pin: int) -> bool:
        return bool(self.sim.io.digital_out[pin])

    def digital_in(self, pin: int) -> bool:
        return bool(self.sim.io.digital_in[pin])

    def set_analog_out(self, pin: int, fraction: float) -> None:
        self.sim.io = self.sim.io.with_analog_out(pin, fraction)

    def set_payload(self, mass: float, cog: list[float]) -> None:
        self.sim.set_payload(mass, np.array(cog), np.zeros(6))

    def registers(self):
        return self.robot.registers

    def sockets(self):
        if self._sockets is None:
            raise ScriptError('this program has no network: sockets are not available here')
        return self._sockets

    def close(self) -> None:
        """The program has ended: its sockets close."""
        if self._sockets is not None:
            self._sockets.close_all()

    def textmsg(self, text: str) -> None:
        self._log(text)


def _joints6(name: str, value) -> list[float]:
    if not isinstance(value, list) or len(value) != 6 or not all(is_number(v) for v in value):
        raise ScriptError(f'{name} is a list of 6 joint values; got {show(value)}')
    return [float(v) for v in value]


def _positive(name: str, value) -> float:
    if not is_number(value) or not value > 0.0 or not np.isfinite(value):
        raise ScriptError(f'{name} is a number > 0; got {show(value)}')
    return float(value)


def _time(kind: str, value) -> float:
    if not is_number(value) or value < 0.0 or not np.isfinite(value):
        raise ScriptError(f'{kind}: t is a time >= 0 [s]; got {show(value)}')
    return float(value)
