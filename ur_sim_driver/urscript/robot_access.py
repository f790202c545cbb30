"""What a URScript program reads of the robot and sets on it: the interpreter's ``ScriptRobot``, as a mixin of
``ScriptProgram`` (``program.py``, the commander: cycles, threads, moves). Joints, TCP and kinematics with the
robot's TCP (``set_tcp``), the state and the dynamics, tool contact, IO, payload, registers, sockets, interpreter
mode, force mode, freedrive and teach mode, the RTDE watchdogs. Under the simulation lock, as the program runs.

It works on the program's own state (``ScriptProgram.__init__`` makes it): ``sim``, ``robot``, ``ik`` and
``_flange_ik``, the reference ``_ref`` and move ``_move``, the joint history, the cycle count, the settings and
hooks it was given.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ur_sim_driver.description.analytic_ik import UrAnalyticIK, nearest_branch
from ur_sim_driver.errors import ScriptError
from ur_sim_driver.motion.force_mode import ForceModeSpec
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.tool_contact import strongest_touch
from ur_sim_driver.robot.external_ft import ExternalFtSensor
from ur_sim_driver.robot.software import SoftwareVersion
from ur_sim_driver.urscript.interpreter_session import InterpreterSession
from ur_sim_driver.urscript.moves import tool_jacobian
from ur_sim_driver.urscript.values import Pose

DH_FROM_BASE_LINK = np.diag([-1.0, -1.0, 1.0, 1.0])  # the controller's base frame is DH frame 0
STEADY_SPEED = 1e-3  # [rad/s] is_steady(): every joint slower than this, and no motion commanded
# get_freedrive_status: the Jacobian's smallest singular value below these is near / too near a singularity (UR does
# not publish its rule; these make a wrist within a few degrees of straight "near")
NEAR_SINGULAR, TOO_NEAR_SINGULAR = 0.05, 0.01


class RobotAccess:
    """The ScriptRobot methods of a ScriptProgram."""

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
                            base_pose=DH_FROM_BASE_LINK)

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

    def tcp_force(self) -> np.ndarray:
        """(6,) the force [N] and torque [N m] at the TCP, base axes (``Simulator.tcp_force``)."""
        return self.sim.tcp_force()

    def enable_external_ft(self, sensor: ExternalFtSensor | None) -> None:
        """ft_rtde_input_enable: the force-torque reading from RTDE's external_force_torque (None: the arm's own
        sensor). It stays after the program, as the robot's setting does."""
        self.sim.external_ft = sensor

    def software_version(self) -> SoftwareVersion:
        return self.sim.software_version

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
