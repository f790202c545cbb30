"""The simulation loop's thread: one control cycle after another, paced to the wall clock or as fast as possible.

In real time (``real_time_factor`` > 0) a cycle is due every ``control_dt / real_time_factor`` of wall time, counted
from the stamps' origin (``conversions.RobotClock``): the first cycles catch up the time between taking the origin and
starting, after that a loop more than ``CATCH_UP_LIMIT`` behind starts counting afresh instead of racing. In real
time the thread runs under SCHED_FIFO where allowed, as ros2_control_node's update thread does. In step with a client
(``pace_topic``) each cycle first waits at the pace gate. MuJoCo's passive viewer, where asked for and a display
exists, is synced at ``VIEWER_FRAME_PERIOD``.
"""
from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable

from rclpy.context import Context

from ur_sim_driver.motion.conversions import RobotClock
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.ros.pace_gate import PaceGate

VIEWER_FRAME_PERIOD = 1.0 / 30.0  # [s] of wall time
CATCH_UP_LIMIT = 0.1  # [s] of wall time the real-time loop may fall behind before it stops catching up
JOIN_TIMEOUT = 5.0  # [s] of wall time to wait for the loop to finish its cycle at stop


class SimLoop:
    """Runs `step` (one control cycle) in a thread of its own until :meth:`stop`.

    Args:
        step: one control cycle (the node's ``step_once``).
        sim: the simulator (its time and control period; the viewer shows its model).
        cfg: ``real_time_factor``, ``thread_priority`` and ``viewer``.
        clock: the stamps' clock: a non-zero origin is the wall time the first cycles catch up from.
        pace: the wait for a client in step with the loop, or None.
        lock: held while the viewer reads the simulation.
        context: the node's context (a loop failing after it shut down is shutting down, not failing).
        logger: the node's logger.
    """

    def __init__(self, step: Callable[[], None], sim: Simulator, cfg: SimConfig, clock: RobotClock,
                 pace: PaceGate | None, lock: threading.Lock, context: Context, logger) -> None:
        self._step = step
        self._sim = sim
        self._cfg = cfg
        self._clock = clock
        self._pace = pace
        self._lock = lock
        self._context = context
        self._logger = logger
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='ur_sim_loop', daemon=True)

    def start(self) -> None:
        self._thread.start()

    @property
    def native_id(self) -> int | None:
        """The loop thread's id in the system (its scheduling can be read with it), None before it started."""
        return self._thread.native_id

    def stop(self) -> None:
        """Ask the loop to end and wait (at most ``JOIN_TIMEOUT``) for its cycle to finish."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=JOIN_TIMEOUT)

    def _open_viewer(self):
        """MuJoCo's passive viewer where a display exists (`viewer: true`), else None with a warning."""
        if not self._cfg.viewer:
            return None
        if not (os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY')):
            self._logger.warning('viewer: true but no display (DISPLAY is unset); running without a viewer')
            return None
        try:
            import mujoco.viewer
            return mujoco.viewer.launch_passive(self._sim.physics.model, self._sim.physics.data)
        except Exception as exc:  # a broken GL setup must not stop the simulation
            self._logger.warning(f'viewer could not be opened ({exc!r}); running without a viewer')
            return None

    def _run(self) -> None:
        viewer = self._open_viewer()
        next_frame = 0.0
        dt = self._sim.control_dt
        rtf = self._cfg.real_time_factor
        wall_period = dt / rtf if rtf > 0 else 0.0
        next_wall = time.perf_counter()
        # Stamped from the wall clock at start (the clock's origin): the first cycles catch up the time since.
        starting = (time.time_ns() - self._clock.origin_ns) * 1e-9 if self._clock.origin_ns else 0.0
        next_wall -= starting
        if wall_period > 0.0:
            self._real_time_priority()
        try:
            while not self._stop.is_set():
                if self._pace is not None:
                    self._pace.wait(self._sim.time - dt, dt, self._stop)
                self._step()
                if viewer is not None and time.perf_counter() >= next_frame:
                    with self._lock:
                        viewer.sync()
                    next_frame = time.perf_counter() + VIEWER_FRAME_PERIOD
                if wall_period > 0.0:
                    next_wall += wall_period
                    delay = next_wall - time.perf_counter()
                    if delay > 0.0:
                        time.sleep(delay)
                    elif delay < -CATCH_UP_LIMIT and self._sim.time > starting:
                        next_wall = time.perf_counter()
                # As fast as possible the loop never yields on its own: the executor's threads get the GIL within
                # the switch interval (main.GIL_SWITCH_INTERVAL) when they ask for it. A sleep(0) every 8 cycles cost
                # 10 to 20 % of the rate (each one a system call that may sleep for the timer slack).
        except Exception as exc:
            if self._stop.is_set() or not self._context.ok():
                return  # shutting down: publishers may already be gone
            self._logger.fatal(f'simulation loop stopped: {exc!r}')
            raise
        finally:
            if viewer is not None:
                viewer.close()

    def _real_time_priority(self) -> None:
        """Run this (the loop's) thread under SCHED_FIFO at `thread_priority`, as ros2_control_node runs its
        update thread, so that other processes' load does not delay its cycles. Only in real-time mode: as fast
        as possible, a FIFO thread that never sleeps would starve the rest of the machine."""
        priority = self._cfg.thread_priority
        if priority == 0:
            return
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        except OSError as exc:  # not permitted (no CAP_SYS_NICE / rtprio limit): run as before, and say so
            self._logger.warning(
                f'could not run the simulation loop under SCHED_FIFO priority {priority} ({exc.strerror}); it runs '
                'at normal priority and its period may jitter under load (allow it with an rtprio limit, e.g. in '
                '/etc/security/limits.conf, or set thread_priority:=0 to silence this)')
