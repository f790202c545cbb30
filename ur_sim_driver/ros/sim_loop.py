"""The simulation loop's thread: one control cycle after another, paced to the wall clock or as fast as possible.

In real time (``real_time_factor`` > 0) a cycle is due every ``control_dt / real_time_factor`` of wall time. On the
system clock (the stamps' origin, ``conversions.RobotClock``, is the wall clock at start; moved to the loop's start
before its first cycle) robot time is owed to the wall clock, as the driver's stamps are its controller manager's
now(): after a stall the loop simulates the cycles it is behind as fast as it can, so the stamps rejoin the system
clock with the physics continuous. Beyond ``MAX_BEHIND`` (a long stall, a machine that cannot run faster than real
time) it gives up the lag instead: the origin moves forward by it, and the stamps jump to the system clock. Counted
from 0 (in step with a client), a loop more than ``CATCH_UP_LIMIT`` behind starts counting afresh instead of racing.
In real time the thread runs under SCHED_FIFO where allowed, as ros2_control_node's update thread does. In step with a
client (``pace_topic``) each cycle first waits at the pace gate. MuJoCo's passive viewer, where asked for and a
display exists, is synced at ``VIEWER_FRAME_PERIOD``.
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
CATCH_UP_LIMIT = 0.1  # [s] of wall time a loop counted from 0 may fall behind before it stops catching up
# [s] of wall time a loop on the system clock may fall behind before it moves the origin instead of catching up: a
# 0.6 s stall is caught up (at some 3 times real time: 0.3 s), a machine slower than real time falls at most this far
# behind before its stamps jump back to the system clock.
MAX_BEHIND = 1.0
JOIN_TIMEOUT = 5.0  # [s] of wall time to wait for the loop to finish its cycle at stop


class SimLoop:
    """Runs `step` (one control cycle) in a thread of its own until :meth:`stop`.

    Args:
        step: one control cycle (the node's ``step_once``).
        sim: the simulator (its time and control period; the viewer shows its model).
        cfg: ``real_time_factor``, ``thread_priority`` and ``viewer``.
        clock: the stamps' clock: a non-zero origin is the wall time the cycles catch up to; the loop moves it.
        on_origin: called with the new origin [ns] when the loop moved it (before its next cycle).
        pace: the wait for a client in step with the loop, or None.
        lock: held while the viewer reads the simulation.
        context: the node's context (a loop failing after it shut down is shutting down, not failing).
        logger: the node's logger.
    """

    def __init__(self, step: Callable[[], None], sim: Simulator, cfg: SimConfig, clock: RobotClock,
                 pace: PaceGate | None, lock: threading.Lock, context: Context, logger,
                 on_origin: Callable[[int], None] = lambda origin_ns: None) -> None:
        self._step = step
        self._on_origin = on_origin
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
        on_system_clock = wall_period > 0.0 and self._clock.origin_ns != 0
        # When the next cycle is due (perf_counter [s]). On the system clock robot time 0 was due at the origin,
        # taken before setting up: the origin moves to now instead.
        next_wall = time.perf_counter()
        if on_system_clock:
            owed = (time.time_ns() - self._clock.origin_ns) * 1e-9 - self._sim.time / rtf  # [s] of wall time
            next_wall = self._give_up_lag(next_wall - owed, rtf, at_start=True)
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
                    elif on_system_clock:
                        # Behind: the next cycle at once. (Dropping the lag here, as below, had kept the stamps
                        # behind the system clock for good after every stall.)
                        next_wall = self._give_up_lag(next_wall, rtf)
                    elif delay < -CATCH_UP_LIMIT:
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

    def _give_up_lag(self, due: float, rtf: float, at_start: bool = False) -> float:
        """When the next cycle is due (perf_counter [s]), given that it was `due`: the same while at most
        `MAX_BEHIND` behind (the loop catches up), else now, with the stamps' origin moved forward by the robot time
        not simulated (the wall time behind times `rtf`), so that the stamps rejoin the system clock while the
        simulated state goes on from where it was. Goals keep their robot time: one under way ends that much later
        on the stamps. `at_start`: before the first cycle, when nothing is stamped yet, any lag is given up, quietly
        (racing through the set-up time, 0.5 s or more, gained nothing; stopped short of it, it had left the stamps
        0.2 s behind for good)."""
        behind = time.perf_counter() - due
        if behind <= (0.0 if at_start else MAX_BEHIND):
            return due
        skipped = round(behind * rtf * 1e9)  # [ns]
        self._clock.origin_ns += skipped  # between cycles; this thread is its one writer
        self._on_origin(self._clock.origin_ns)
        if not at_start:
            self._logger.warning(
                f'the simulation loop was {behind:.2f} s behind the system clock (more than {MAX_BEHIND:.1f} s: a '
                f'stall, or a machine that cannot keep real time); its stamps skip {skipped * 1e-9:.2f} s to rejoin '
                'it, the robot goes on from where it was')
        return due + behind

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
