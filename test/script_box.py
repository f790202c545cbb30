"""A simulated robot with its URScript program slot, stepped cycle by cycle as the simulation loop steps it (no ROS):
shared by the URScript program tests and the ur_rtde control loop tests."""
from __future__ import annotations

import numpy as np

from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.ports.script_sockets import ScriptSockets
from ur_sim_driver.robot.robot_state import RobotState
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.robot.software import parse_version
from ur_sim_driver.urscript.runner import RUNTIME_ERROR, ScriptRunner

READY = [0.0, -1.2, 1.2, -1.57, -1.57, 0.0]  # [rad] an elbow-bent pose, away from singularities
# URScript lines for a program's body: a global `ticks` and a thread `counter` that adds one to it every cycle
COUNTER = '''  global ticks = 0
  thread counter():
    while True:
      ticks = ticks + 1
      sync()
    end
  end
'''


class Box:
    """The simulated robot with its program slot, stepped cycle by cycle as the simulation loop steps it."""

    def __init__(self, q0=READY, factor: float = 1.0, before_step=None, software_version: str = '') -> None:
        """`before_step`: called before each control cycle (a test's loopback server answers there);
        `software_version`: the controller's ('': the type's default)."""
        version = parse_version(software_version, 'ur5e')
        self.sim = Simulator(SimConfig(ur_type='ur5e', initial_positions=tuple(q0), software_version=version))
        self.robot = RobotState()
        self.factor = factor
        self.log: list[str] = []
        self.network_log: list[str] = []
        self.before_step = before_step
        self.force_modes: list = []  # what programs asked of the robot's force mode (no force mode runs here)
        self.runner = ScriptRunner(self.sim, self.robot, lambda: self.factor, self.log.append,
                                   lambda: ScriptSockets(lambda: self.sim.time, self.network_log.append),
                                   self.force_modes.append)
        self.events = []
        self.runner.listen(self.events.append)
        self.q: list[np.ndarray] = []
        self.tcp: list[np.ndarray] = []

    def run(self, source: str, limit: float = 30.0) -> float:
        """Submit `source` and step until it ends; the simulated time it took [s]."""
        self.runner.submit(source)
        t0 = self.sim.time
        while self.runner.current is not None:
            assert self.sim.time - t0 < limit, 'the program did not end'
            self.step()
        return self.sim.time - t0

    def step(self) -> None:
        if self.before_step is not None:
            self.before_step()
        state = self.sim.state()
        program = self.runner.commander()
        if program is None:  # no program: the robot holds where it is
            zero = np.zeros(6)
            sample, stop = TrajectorySample(state.q, zero, zero, 0, True), state.q
        else:
            sample, stop = program.command(state, self.sim.control_dt)
        torques = program.torques() if program is not None else None
        if program is not None and program.free:  # freedrive, torque control: as the simulation loop does
            self.sim.advance_free(state)
        elif torques is not None:
            self.sim.advance_torque(state, torques, program.friction_scales)
        else:
            self.sim.advance(state, sample, stop)
        self.runner.after_cycle()
        self.q.append(self.sim.state().q)
        self.tcp.append(self.sim.tcp_pose()[0])

    def kinds(self) -> list[str]:
        return [e.kind for e in self.events]

    def errors(self) -> list:
        return [e for e in self.events if e.kind == RUNTIME_ERROR]
