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
from dataclasses import replace

import numpy as np

from ur_sim_driver.description.analytic_ik import UrAnalyticIK, nearest_branch
from ur_sim_driver.errors import ConfigError, ScriptError
from ur_sim_driver.motion.force_mode import ForceModeSpec
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.physics.tool_contact import strongest_touch
from ur_sim_driver.robot.robot_state import RobotState
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.urscript.grammar import parse
from ur_sim_driver.urscript.interpreter import Interpreter
from ur_sim_driver.urscript.interpreter_session import InterpreterSession
from ur_sim_driver.urscript.moves import Arc, JointLine, Move, Servo, Speed, ToolLine, ToolSpeed, tool_jacobian
from ur_sim_driver.urscript.values import Pose, Request, is_number, show

END_DECELERATION = 2.0  # [rad/s^2] a program that ends while the arm moves at speed stops it with this
STEADY_SPEED = 1e-3  # [rad/s] is_steady(): every joint slower than this, and no motion commanded
# get_freedrive_status: the Jacobian's smallest singular value below these is near / too near a singularity (UR does
# not publish its rule; these make a wrist within a few degrees of straight "near")
NEAR_SINGULAR, TOO_NEAR_SINGULAR = 0.05, 0.01
ABORT_DECELERATION = 4.0  # [rad/s^2] the interpreter socket's abort stops a movej or movel with this
HISTORY = 1250  # control cycles of actual joint positions kept for get_actual_joint_positions_history
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
        self.interpreter = Interpreter(parse(source), self)
        self.name = self.interpreter.name or name
        self.secondary = self.interpreter.secondary
        self.sim, self.robot, self._factor, self._log = sim, robot, factor, log
        self._sockets = sockets
        self._session = session if session is not None else InterpreterSession()
        self._force_mode = force_mode
        self.in_force_mode = False
        self._flange_ik = UrAnalyticIK(sim.params.dh, base_pose=_DH_FROM_BASE_LINK)  # tool0
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

    def direct_torque(self, torques: np.ndarray) -> None:
        """direct_torque: these joint torques [N m] for this control cycle; the arm is out of the servo's hands while
        a thread calls it every cycle (the current move ends)."""
        self._move = None
        self._torques, self._torque_cycle = np.array(torques, float), self._cycle

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

    def actual_q(self) -> np.ndarray:
        return self.sim.state().q

    def actual_qd(self) -> np.ndarray:
        return self.sim.state().qd

    def target_q(self) -> np.ndarray:
        return self._ref.positions if self._ref is not None else self.sim.state().q

    def target_qd(self) -> np.ndarray:
        return self._ref.velocities if self._ref is not None else np.zeros(len(self.sim.state().q))

    def steptime(self) -> float:
        return self.sim.control_dt

    def joint_history(self, steps: int) -> np.ndarray:
        """The actual joint positions `steps` control cycles ago (0: now; the oldest kept when further back)."""
        if not self._history:
            return self.sim.state().q
        return self._history[-1 - min(steps, len(self._history) - 1)]

    def forward_kin(self, q: np.ndarray, tcp: Pose | None) -> Pose:
        """The TCP pose at `q`: `tcp` from tool0 (None: the robot's TCP, set_tcp's)."""
        q = np.asarray(q, float)
        return Pose.from_matrix(self.ik.fk(q) if tcp is None else self._flange_ik.fk(q) @ tcp.matrix())

    def _tcp_ik(self) -> UrAnalyticIK:
        return UrAnalyticIK(self.sim.params.dh, tool=Pose(tuple(self.sim.tcp_offset)).matrix(),
                            base_pose=_DH_FROM_BASE_LINK)

    def set_tcp(self, pose: Pose) -> None:
        """The robot's TCP from now on, for this program's poses and moves and for every interface."""
        self.sim.set_tcp(np.array(pose.values))
        self.ik = self._tcp_ik()

    def tcp_offset(self) -> Pose:
        return Pose(tuple(float(v) for v in self.sim.tcp_offset))

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        return tool_jacobian(self.ik, q)

    def tcp_speed(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """(6,) the TCP's linear [m/s] and angular [rad/s] velocity, base axes."""
        return tool_jacobian(self.ik, q) @ np.asarray(qd, float)

    def within_joint_limits(self, q: np.ndarray) -> bool:
        p = self.sim.params
        return bool(np.all((q >= p.q_min) & (q <= p.q_max)))

    def tool_contact(self, direction: np.ndarray) -> int:
        """tool_contact(): 0 without a contact; with one, the control cycles since it began (at least 1), the steps
        back to the joints of just before it. Any contact of the tool over the threshold counts, whatever
        `direction`."""
        if not self.tool_touch():
            self._touch_from = None
            return 0
        if self._touch_from is None:
            self._touch_from = self._cycle
        return self._cycle - self._touch_from + 1

    def set_watchdog(self, variable: str, min_frequency: float, action: str) -> None:
        """rtde_set_watchdog: from now on `variable` must be written over RTDE at least `min_frequency` [Hz] times a
        second, else `action` ('ignore', 'pause', 'stop'); 0 Hz removes the watchdog."""
        if min_frequency <= 0.0:
            self._watchdogs.pop(variable, None)
            return
        self._watchdogs[variable] = (1.0 / min_frequency, action, self.sim.time)

    def _watchdog_fired(self) -> bool:
        """A watchdog's variable was not written in time: its action (the program pauses or stops; True) or a log
        line ('ignore', once a silence)."""
        now = self.sim.time
        for variable, (gap, action, since) in list(self._watchdogs.items()):
            last = max(self.robot.rtde_inputs.get(variable, since), since)
            if now - last <= gap + 1e-9:
                continue
            message = (f'rtde_set_watchdog: {variable} was not written for {now - last:.3f} s (at least every '
                       f'{gap:.3f} s); action {action}')
            if action == 'ignore':
                self._log(message)
                self._watchdogs[variable] = (gap, action, now)
                continue
            self._log(message)
            if action == 'pause':
                self.robot.pause()
            else:
                self.robot.stop()
            return True
        return False

    def target_waypoint(self) -> Pose:
        """The TCP pose the current move ends at; the target TCP pose now when no move with an end runs."""
        if self._move is not None and self._waypoint is not None and not self.move_finished():
            return self.forward_kin(self._waypoint, None)
        return self.forward_kin(self.target_q(), None)

    def joint_torques(self) -> np.ndarray:
        """(n,) [N m] the joints' torques less what the robot's model needs to move the arm as it moves now (M(q)
        qdd of the target, Coriolis, and gravity with the payload and gravity it believes in: set_payload,
        set_gravity): what the environment, and a payload other than the one set, load it with."""
        mass, _ = self.sim.physics.dynamics()
        model = mass @ self.target_qdd() + self.sim.physics.coriolis_torques() + self.sim.gravity_compensation()
        return self.sim.state().effort - model

    def freedrive_status(self) -> int:
        """0 normal, 1 near a singularity, 2 too close to one (by the Jacobian's smallest singular value at the
        actual joints: below NEAR_SINGULAR and TOO_NEAR_SINGULAR)."""
        smallest = float(np.linalg.svd(tool_jacobian(self.ik, self.sim.state().q), compute_uv=False)[-1])
        return 2 if smallest < TOO_NEAR_SINGULAR else 1 if smallest < NEAR_SINGULAR else 0

    def target_qdd(self) -> np.ndarray:
        return self._ref.accelerations if self._ref is not None else np.zeros(len(self.sim.state().q))

    def mass_matrix(self) -> np.ndarray:
        """(n, n) [kg m^2] at the actual joints, with the tool and the mounted payload."""
        return self.sim.physics.dynamics()[0]

    def coriolis(self) -> np.ndarray:
        return self.sim.physics.coriolis_torques()

    def jacobian_rate(self, q: np.ndarray, qd: np.ndarray, step: float = 1e-6) -> np.ndarray:
        """(6, n) d/dt of the tool Jacobian moving at `qd` [rad/s], by central differences along the motion."""
        return (tool_jacobian(self.ik, q + step * qd) - tool_jacobian(self.ik, q - step * qd)) / (2.0 * step)

    def steady(self) -> bool:
        """The arm at rest: no motion commanded and the joints slower than STEADY_SPEED."""
        return self.move_finished() and float(np.abs(self.sim.state().qd).max()) < STEADY_SPEED

    def set_free(self, free: bool) -> None:
        """Enter or leave freedrive: the current move ends; leaving it, the arm holds where it can stop from the speed
        it was pushed to, braking as hard as the robot does (as /freedrive_mode_controller's end)."""
        if free:
            self._move = None
        elif self.free:
            hold = self.sim.stopping_point(self.sim.state())
            zero = np.zeros_like(hold)
            self._ref = TrajectorySample(hold, zero, zero.copy(), 0, True)
        self.free = free

    def protective_stop(self) -> None:
        self.robot.protective_stop(self.sim.time, 'protective_stop() called by the program')

    def zero_ftsensor(self) -> None:
        self.sim.zero_ftsensor()

    def set_gravity(self, anti_gravity: list[float]) -> None:
        self.sim.set_gravity(np.array(anti_gravity, float))

    def payload(self) -> tuple[float, list[float], list[float]]:
        """What the robot believes is mounted: mass [kg], cog (tool0) [m], inertia (6,) [kg m^2]."""
        p = self.sim.payload
        return float(p.mass), [float(v) for v in p.cog], [float(v) for v in p.inertia]

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

    def set_tool_voltage(self, volts: int) -> None:
        self.sim.io = self.sim.io.with_tool_voltage(volts)

    def set_analog_out(self, pin: int, fraction: float) -> None:
        self.sim.io = self.sim.io.with_analog_out(pin, fraction)

    def set_payload(self, mass: float, cog: list[float], inertia: list[float] | None = None) -> None:
        self.sim.set_payload(mass, np.array(cog), np.zeros(6) if inertia is None else np.array(inertia))

    def registers(self):
        return self.robot.registers

    def sockets(self):
        if self._sockets is None:
            raise ScriptError('this program has no network: sockets are not available here')
        return self._sockets

    def interpreter_session(self) -> InterpreterSession:
        return self._session

    def set_force_mode(self, spec: ForceModeSpec | None) -> None:
        """force_mode (`spec`: the task frame in base, the gain and damping force_mode_set_* gave) or end_force_mode
        (None)."""
        if self._force_mode is None:
            raise ScriptError('force mode needs the simulation loop: this robot has none')
        if spec is not None:
            spec = replace(spec, damping=self.force_settings['damping'],
                           gain_scaling=self.force_settings['gain_scaling'])
        elif not self.in_force_mode:
            return
        self._force_mode(spec)
        self.in_force_mode = spec is not None

    def close(self) -> None:
        """The program has ended: its sockets close, and interpreter mode with it."""
        if self._sockets is not None:
            self._sockets.close_all()
        if self._session.active:
            self._session.leave(True)
        if self.in_force_mode:  # the robot ends force mode with the program
            self.set_force_mode(None)

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
