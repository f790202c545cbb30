"""Running a plan on a robot through FollowJointTrajectory: one goal per segment, with the job's tolerances.

Shared by the planner node and the studio: progress from the goal feedback, the bead's joint states recorded,
a message for every result code, and a stop request that cancels the active goal. The plan's tip path is published
(planned_path.py) and the whole run recorded as a rosbag2 in MCAP (bag_recorder.py); a run that cannot be
recorded goes on without its bag.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path

from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution.bag_recorder import BagRecorder
from ur_glue_planner.execution.bead_listener import BeadListener
from ur_glue_planner.execution.client import URClient
from ur_glue_planner.execution.dispenser_io import DispenserIO
from ur_glue_planner.execution.planned_path import publish_planned_path, tf_prefix_of
from ur_glue_planner.execution.switch_timer import SwitchEvent
from ur_glue_planner.execution.trajectory_goal import GoalOutcome
from ur_glue_planner.motion.plan import GluePlan
from ur_glue_planner.report.glue_report import Executed

#: ``on_progress(segment name, fraction of its duration done, max joint tracking error [rad])``.
Progress = Callable[[str, float, float], None]

FLOW_FALL = 7.0  # time constants from the flow's fall to below 0.1 % of its rate
BEAD_DELIVERY = 1.0  # [s] of wall time allowed at least for the bead goal to reach the controller before it starts
# In step with ur_sim: the bead goal's start this far [s of robot time] beyond the lead; ur_sim is held half of it
# before the start until the goal executes (the client's view of robot time may lag ur_sim's by FREE_AHEAD).
PACED_DELIVERY = 0.3
EXECUTING_TIMEOUT = 30.0  # [s] of wall time for the server to report the bead goal executing (a hang guard)
RECORD_RATE = 50.0  # [Hz] nominal; the report uses every message received (exact stamps)
BAG_ROOT = Path('out') / 'bags'  # the bags of runs given no bag directory (the studio's), one per run
MESSAGES = {
    0: 'bead completed',
    -1: 'the goal was invalid or preempted by another command',
    -2: 'the goal named joints the controller does not have',
    -3: 'the trajectory started in the past: check that this node and the driver share a clock (use_sim_time)',
    -4: 'the robot left the path tolerance (it could not follow the trajectory)',
    -5: 'the robot did not reach the goal tolerance in time',
}


def describe(outcome: GoalOutcome) -> str:
    """What a goal's result means, with its code, status and the server's text."""
    return (f'{MESSAGES.get(outcome.error_code, "unknown error code")} (error_code {outcome.error_code}, '
            f'status {outcome.status}): {outcome.error_string}')


class Interrupted(Exception):
    """SIGINT or SIGTERM arrived while a goal was running; the goal has been cancelled."""


def _progress(name: str, t0: float, duration: float, log: Callable[[str], None], on_progress: Progress | None):
    last = [0.0]

    def show(feedback) -> None:
        t = feedback.header.stamp.sec + feedback.header.stamp.nanosec * 1e-9 - t0
        error = max((abs(e) for e in feedback.error.positions), default=0.0)
        fraction = min(max(t / duration, 0.0), 1.0)
        if on_progress is not None:
            on_progress(name, fraction, error)
        now = time.monotonic()
        if now - last[0] < 0.5:
            return
        last[0] = now
        log(f'  [{name}] {100.0 * fraction:5.1f} % of {duration:.1f} s, max joint tracking error '
            f'{error * 1e3:.3f} mrad')
    return show


def _print(text: str) -> None:
    print(text, flush=True)


def dispenser_events(plan: GluePlan) -> list[SwitchEvent]:
    """The plan's gun switching as events on the bead segment's trajectory clock."""
    d = plan.dispense
    return [SwitchEvent(d.t_on, d.pin, True, 'gun on'), SwitchEvent(d.t_off, d.pin, False, 'gun off')]


def default_bag_dir(plan: GluePlan) -> Path:
    """BAG_ROOT/<local time>_<job file name>_<method>: where a run given no bag directory is recorded."""
    name = Path(plan.job.source_file).stem if plan.job.source_file else 'glue_job'
    return BAG_ROOT / f'{time.strftime("%Y%m%d-%H%M%S")}_{name}_{plan.method}'


def start_bag(ur: URClient, plan: GluePlan, bag_dir: str | Path | None,
              log: Callable[[str], None] = _print) -> BagRecorder | None:
    """Publish the plan's tip path and start recording the run into `bag_dir` (None: `default_bag_dir`); None
    when the recording cannot start (it says why: the run goes on without a bag)."""
    try:
        publish_planned_path(ur.node, ur.prefix, plan, tf_prefix_of(ur.joint_names) + 'base_link', ur.now())
    except Exception as exc:  # noqa: BLE001 - a viewer's topic, never a reason to stop the run
        log(f'planned path: not published ({type(exc).__name__}: {exc})')
    try:
        return BagRecorder(ur.context, bag_dir if bag_dir is not None else default_bag_dir(plan), ur.prefix,
                           log=log).start()
    except Exception as exc:  # noqa: BLE001 - as above
        log(f'bag: not recording ({type(exc).__name__}: {exc}); the run goes on')
        return None


def _wait_executing(goal) -> None:
    """Until the server reports `goal` executing: ur_sim's gateway hands a goal to the controller before it says so.
    Wall time passes, robot time does not (ur_sim is held); a poll, as the status has no event to wait on here."""
    deadline = time.monotonic() + EXECUTING_TIMEOUT
    while not goal.executing:
        if time.monotonic() > deadline:
            raise ClientError(f'the bead goal was not reported executing within {EXECUTING_TIMEOUT:.0f} s')
        time.sleep(0.001)


def execute(ur: URClient, plan: GluePlan, stop: threading.Event, log: Callable[[str], None] = _print,
            on_progress: Progress | None = None, gun: DispenserIO | None = None,
            bead: BeadListener | None = None, bag_dir: str | Path | None = None,
            record: bool = True) -> tuple[GoalOutcome, Executed | None]:
    """Run the plan's segments in order; returns the last outcome and the bead's recorded joint states.

    Args:
        ur: Connected client.
        plan: The plan (its approach starts where the robot is).
        stop: Set to cancel: the active goal is cancelled and Interrupted raised.
        log: Receives the progress and result lines.
        on_progress: Called on every feedback message.
        gun: Switches the glue gun during the bead (None: no dispensing). It is switched off at the end of
            the bead, and at once on a failure or a cancel.
        bead: The simulator's bead (None: not collected): cleared before the run, read after it.
        bag_dir: The run's rosbag2 directory (None: `default_bag_dir`), recorded from before the first segment
            until after the final bead is read; `record` False: no bag.
    """
    job = plan.job
    path_tol = ur.tolerances(job.tolerances.path_position)
    goal_tol = ur.tolerances(job.tolerances.goal_position)
    recorder, outcome, run = None, None, None
    whole = ur.start_recording(RECORD_RATE)
    bead_start, switches, deposit = None, (), None
    if bead is not None:
        bead.clear()
    if gun is not None:
        # the gun starts off, and the call path to set_io is exercised before it matters: a first request can
        # take far longer than the next ones (DDS matching of the response path)
        gun.off(plan.dispense.pin, timeout=15.0)
    bag = start_bag(ur, plan, bag_dir, log) if record else None
    try:
        for seg in plan.segments():
            early = max(0.0, -plan.dispense.t_on) if (seg.name == 'bead' and gun is not None) else 0.0
            # Built before the start is chosen: a long goal takes a while to build on a loaded machine.
            request = ur.trajectory_goal(seg.q, seg.qd, seg.qdd, seg.times, path_tolerance=path_tol,
                                         goal_tolerance=goal_tol, goal_time_tolerance=job.tolerances.goal_time)
            paced = seg.name == 'bead' and gun is not None and gun.paced
            if paced:
                # In step with ur_sim (pace_topic): it waits before the start until the goal is with its controller
                # (below), so the stamp needs no margin for the delivery.
                t0 = start = ur.now() + 0.1 + early + PACED_DELIVERY
                ahead = start - ur.now()
            elif seg.name == 'bead':
                # The bead's start is fixed in advance (the gun switches on its clock): a stamp ahead, with a
                # margin for the goal's delivery [s of wall time] that grows with the answer times seen so far.
                t0 = start = ur.start_time(lead=0.1 + early, delivery=BEAD_DELIVERY, points=len(seg.times))
                ahead = start - ur.now()  # [s] of robot time
            else:
                # The moves around it start on arrival: a stamp that a slow delivery put in the past would make
                # the controller sample the trajectory past its start, a jump that aborts the goal.
                t0, start = ur.now(), 0.0
            if seg.name == 'bead':
                recorder = ur.start_recording(RECORD_RATE, t0)
                bead_start = t0
                if gun is not None:
                    gun.arm(dispenser_events(plan), t0)
                    d = plan.dispense
                    log(f'dispenser: output {d.pin} on at t = {d.t_on:.3f} s and off at t = {d.t_off:.3f} s of '
                        f'the bead (lead {d.lead:.3f} s, lag {d.lag:.3f} s)')
            log(f'{seg.name}: {len(seg.times)} points, {seg.duration:.2f} s')
            feedback = _progress(seg.name, t0, seg.duration, log, on_progress)
            if paced:
                with gun.hold(start - PACED_DELIVERY / 2):
                    goal = ur.send_goal(request, start_time=start, wait=False, feedback_callback=feedback)
                    _wait_executing(goal)
            else:
                goal = ur.send_goal(request, start_time=start, wait=False, feedback_callback=feedback)
            if seg.name == 'bead':
                log(f'  accepted {1e3 * ur.goal_answers[-1][0]:.0f} ms after sending, its start stamped '
                    f'{ahead:.1f} s ahead')
            while not goal.done:
                if stop.is_set():
                    log(f'\ninterrupted: cancelling the {seg.name} goal')
                    # The cancel goes first and the gun is switched off while it travels: each waits for its
                    # answer, which a loaded machine can delay by seconds (the robot ran on meanwhile).
                    goal.cancel(meanwhile=(lambda: gun.off(plan.dispense.pin)) if gun is not None else None)
                    goal.wait(timeout=10.0)
                    raise Interrupted(seg.name)
                time.sleep(0.02)
            outcome = goal.wait()
            if recorder is not None:
                if gun is not None:
                    missed = gun.disarm()
                    if missed and outcome.succeeded:
                        log(f'dispenser: {", ".join(e.what for e in missed)} did not happen before the bead ended')
                    gun.off(plan.dispense.pin)
                    ur.sleep(0.05)  # the off state reaches io_states
                    switches = tuple(gun.collect()) + tuple(gun.changes)
                # the gun's off delay and its flow's fall: the bead grows for a moment after the switch, until the
                # flow is below 0.1 % of its rate (ur_sim's idle: ln(1000) < 7 time constants) and ur_sim
                # publishes the bead's last message
                fall = FLOW_FALL * job.dispenser.time_constant
                ur.sleep(0.2 + (job.dispenser.off_delay + fall if gun else 0.0))
                rec = ur.stop_recording(recorder, raw=True)
                recorder = None
                deposit = bead.final() if bead is not None else None
                run = Executed(rec.t, rec.q, rec.qd)
            if not outcome.succeeded:
                log(f'{seg.name} failed: {describe(outcome)}')
                break
    finally:
        if gun is not None:
            try:
                gun.off(plan.dispense.pin)
            except Exception as exc:  # noqa: BLE001 - the original failure matters more; say this one too
                log(f'dispenser: could not switch output {plan.dispense.pin} off: {exc}')
        rec_all = ur.stop_recording(whole, raw=True)
        if bag is not None:
            try:
                bag.close()
            except Exception as exc:  # noqa: BLE001 - the run's outcome matters more; say this one too
                log(f'bag: could not be closed: {type(exc).__name__}: {exc}')
    if run is not None:
        run = Executed(run.t, run.q, run.qd, whole=rec_all, start_stamp=bead_start, switches=switches,
                       deposit=deposit, whole_t0=whole.start() if rec_all is not None else None)
    return outcome, run
