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

from collections import deque
from collections.abc import Callable

import numpy as np

from ur_sim_driver.description.analytic_ik import UrAnalyticIK
from ur_sim_driver.errors import ConfigError, ScriptError
from ur_sim_driver.motion.force_mode import ForceModeSpec
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.direct_torque import FrictionScales
from ur_sim_driver.robot.robot_state import RobotState
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.urscript.grammar import parse
from ur_sim_driver.urscript.interpreter import Interpreter
from ur_sim_driver.urscript.interpreter_session import InterpreterSession
from ur_sim_driver.urscript.moves import Arc, JointLine, Move, Servo, Speed, ToolLine, ToolSpeed, tool_jacobian
from ur_sim_driver.urscript.robot_access import DH_FROM_BASE_LINK, RobotAccess
from ur_sim_driver.urscript.values import Pose, Request, is_number, show

END_DECELERATION = 2.0  # [rad/s^2] a program that ends while the arm moves at speed stops it with this
ABORT_DECELERATION = 4.0  # [rad/s^2] the interpreter socket's abort stops a movej or movel with this
# optimovel's a and v are fractions of these (ur_sim's rule: UR does not publish the tool's limits the controller
# plans with; the speed is the default safety configuration's tool speed limit)
OPTIMOVEL_SPEED, OPTIMOVEL_ACCELERATION = 1.5, 4.0  # [m/s], [m/s^2]
HISTORY = 1250  # control cycles of actual joint positions kept for get_actual_joint_positions_history


class ScriptProgram(RobotAccess):
    """One program (parsed at construction: a syntax error raises ScriptError and nothing runs).

    Args:
        source: the URScript text.
        sim, robot: the simulated robot (read and changed under the simulation lock).
        factor: the robot's speed scaling factor now, in [0, 1].
        log: where textmsg writes (the robot's log).
        name: the program's name when it defines none (bare statements).
        sockets: its client connections (``ports.script_sockets.ScriptSockets``), closed when it ends; None: a
            program without network (a socket function is then a runtime error).
        session: the robot's interpreter socket queue (interpreter mode); None: one of its own, which no socket
            feeds.
        force_mode: starts (a ForceModeSpec) or ends (None) the robot's force mode; None: force_mode is a runtime
            error.
    """

    def __init__(self, source: str, sim: Simulator, robot: RobotState, factor: Callable[[], float],
                 log: Callable[[str], None], name: str = 'unnamed', sockets=None,
                 session: InterpreterSession | None = None,
                 force_mode: Callable[[ForceModeSpec | None], None] | None = None) -> None:
        self.source = source
        self.sim, self.robot, self._factor, self._log = sim, robot, factor, log  # before the interpreter: its
        # functions depend on the software version the robot runs
        self.interpreter = Interpreter(parse(source), self)
        self.name = self.interpreter.name or name
        self.secondary = self.interpreter.secondary
        self._sockets = sockets
        self._session = session if session is not None else InterpreterSession()
        self._force_mode = force_mode
        self.in_force_mode = False
        self._flange_ik = UrAnalyticIK(sim.params.dh, base_pose=DH_FROM_BASE_LINK)  # tool0
        self.ik = self._tcp_ik()  # the robot's TCP (set_tcp): what poses, moves and kinematics refer to
        self.error: ScriptError | None = None
        self.finished = False  # the program has ended (and the arm was commanded to rest)
        self.threads = self.interpreter.threads
        self._program_done = False
        self._move: Move | None = None
        self._move_t = 0.0  # [s] of the current move's own (scaled) time
        self._ref: TrajectorySample | None = None
        self._history: deque[np.ndarray] = deque(maxlen=HISTORY)  # the actual joints of the last cycles
        self._cycle = 0  # control cycles the program has run
        self._touch_from: int | None = None  # the cycle a tool contact began (tool_contact)
        self.force_settings = {'gain_scaling': 1.0, 'damping': 0.005}  # force_mode_set_gain_scaling, _damping
        self.free = False  # freedrive (teach mode): the robot holds the arm up and lets it be moved
        self._torques: np.ndarray | None = None  # direct_torque's, for the cycle _torque_cycle
        self._torque_cycle = -1
        self.friction_scales: FrictionScales | None = None  # direct_torque's friction compensation
        self._waypoint: np.ndarray | None = None  # the joints at the end of the current move (None: no end)
        # rtde_set_watchdog: RTDE input variable -> (the longest gap between its updates [s], action, since [s])
        self._watchdogs: dict[str, tuple[float, str, float]] = {}
        self._qd_nominal: np.ndarray | None = None  # the current move's velocity this cycle [rad/s]

    # ---- the commander ------------------------------------------------------------------------------------
    def take_over(self, state: ArmState) -> None:
        zero = np.zeros_like(state.q)
        self._ref = TrajectorySample(state.q.copy(), zero, zero.copy(), 0, True)

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        if self._ref is None:
            self.take_over(state)
        self._history.append(state.q.copy())
        self._cycle += 1
        if self.free or self._torque_cycle == self._cycle - 1:
            # freedrive: where the arm is pushed to is where it holds when it ends; torque control that ended: where
            # the arm can stop, braking as hard as the robot does (as it ends the driver's torque control)
            zero = np.zeros_like(state.q)
            hold = state.q.copy() if self.free else self.sim.stopping_point(state)
            self._ref = TrajectorySample(hold, zero, zero.copy(), 0, True)
        factor = self._factor()
        current = self._move
        if current is not None:  # where the current move is now: a move the program starts this cycle starts there
            self._move_t += period * factor
            self._sample(factor)
        self.threads.new_cycle(period)
        if self._watchdogs and self._watchdog_fired():
            return self._ref, self._ref.positions
        if self._sockets is not None:
            self._sockets.flush()
        if self._session.take_abort() and isinstance(self._move, (JointLine, ToolLine)):
            # the interpreter socket's abort: a controlled stop of the movej or movel running now
            self._move = Speed(self._ref.positions, self._nominal_qd(), np.zeros(len(self._ref.positions)),
                               ABORT_DECELERATION, None)
            self._move_t = 0.0
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

    def torques(self) -> np.ndarray | None:
        """The torques direct_torque commanded in this cycle (on top of gravity compensation), or None: the robot's
        servo moves the arm."""
        return self._torques if self._torque_cycle == self._cycle else None

    def direct_torque(self, torques: np.ndarray, scales: FrictionScales) -> None:
        """direct_torque: these joint torques [N m] for this control cycle, the robot compensating the joints'
        friction by `scales`; the arm is out of the servo's hands while a thread calls it every cycle (the current
        move ends)."""
        self._move = None
        self._torques, self._torque_cycle = np.array(torques, float), self._cycle
        self.friction_scales = scales

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
        replaces it), at least until the next cycle."""
        try:
            move = self._build(*request.args)
        except ScriptError as exc:  # the statement that asked: its line
            if exc.line:
                raise
            raise ScriptError(f'line {thread.line}: {exc}', thread.line, thread.column) from None
        self._move = move
        self._move_t = 0.0
        self._qd_nominal = move.sample(0.0)[1]  # a move built next in this same cycle starts from it
        self._waypoint = move.sample(move.duration)[0] if np.isfinite(move.duration) else None
        # It returns when the motion function would, and never before the next cycle: a motion takes at least a
        # control cycle, so a thread that calls one in a loop spends robot time (ur_rtde's speed_thread does).
        cycle = self._cycle
        return lambda: self._cycle > cycle and (self._move is not move or self._move_t >= move.returns_after)

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
        if self.free:
            raise ScriptError(f'{kind}: the robot is in freedrive; end_freedrive_mode() or end_teach_mode() first')
        q0 = self._ref.positions.copy()
        p = self.sim.params
        if kind == 'movej':
            target, a, v, t, _r = args
            q1 = self._joints(kind, target, q0)
            return JointLine(q0, q1, _positive(f'{kind}: a', a), _positive(f'{kind}: v', v), _time(kind, t))
        if kind in ('movel', 'movep', 'servoc'):  # movep, servoc: a line to the pose at v (their blend is not used)
            target, a, v, t, _r = args if kind == 'movel' else (*args[:3], 0.0, args[3])
            return ToolLine(self.ik, q0, self.ik.fk(q0), self._pose_matrix(kind, target), _positive(f'{kind}: a', a),
                            _positive(f'{kind}: v', v), _time(kind, t), self.sim.control_dt, p.q_min, p.q_max,
                            name=kind)
        if kind in ('optimovej', 'optimovel'):  # a and v are fractions of what the arm can do
            target, a, v, r = args
            a, v = _fraction(f'{kind}: a', a), _fraction(f'{kind}: v', v)
            if kind == 'optimovej':  # of the slowest joint's limits: no joint exceeds its own
                return self._build('movej', target, a * p.a_max, v * float(np.min(p.v_max)), 0.0, r)
            return self._build('movel', target, a * OPTIMOVEL_ACCELERATION, v * OPTIMOVEL_SPEED, 0.0, r)
        if kind == 'movec':
            via, target, a, v, _r, mode = args
            if mode not in (0, 1):
                raise ScriptError(f'movec: mode is 0 (orientation from start to end) or 1 (fixed to the arc); '
                                  f'got {show(mode)}')
            t0, t_via, t1 = self.ik.fk(q0), self._pose_matrix(kind, via), self._pose_matrix(kind, target)
            arc = Arc.through(t0[:3, 3], t_via[:3, 3], t1[:3, 3])
            return ToolLine(self.ik, q0, t0, t1, _positive(f'{kind}: a', a), _positive(f'{kind}: v', v), 0.0,
                            self.sim.control_dt, p.q_min, p.q_max, arc=arc, fixed=mode == 1, name=kind)
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

    def _pose_matrix(self, kind: str, target) -> np.ndarray:
        """A move's target as a TCP pose (4, 4): a pose as it is, joints by forward kinematics."""
        return target.matrix() if isinstance(target, Pose) else self.ik.fk(_joints6(kind, target))

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

def _joints6(name: str, value) -> list[float]:
    if not isinstance(value, list) or len(value) != 6 or not all(is_number(v) for v in value):
        raise ScriptError(f'{name} is a list of 6 joint values; got {show(value)}')
    return [float(v) for v in value]


def _positive(name: str, value) -> float:
    if not is_number(value) or not value > 0.0 or not np.isfinite(value):
        raise ScriptError(f'{name} is a number > 0; got {show(value)}')
    return float(value)


def _fraction(name: str, value) -> float:
    if not is_number(value) or not 0.0 < value <= 1.0:
        raise ScriptError(f'{name} is a fraction in (0, 1]; got {show(value)}')
    return float(value)


def _time(kind: str, value) -> float:
    if not is_number(value) or value < 0.0 or not np.isfinite(value):
        raise ScriptError(f'{kind}: t is a time >= 0 [s]; got {show(value)}')
    return float(value)
