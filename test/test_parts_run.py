"""`ur_glue_planner --parts`: generated parts run on ur_sim with and without the measurement's correction, end to end;
and ur_sim in step with a client (pace_topic), which makes the gun's switching independent of the machine's load."""
from __future__ import annotations

import json
import math

import pytest
from conftest import reserve_domain
from mcap.reader import make_reader
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sim_harness import running_sim, wait_for
from test_io_and_status import IO, call
from ur_msgs.srv import SetIO

from ur_glue_planner.parts.command import main

HOME = [0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0]


@pytest.mark.timeout(240)  # one part: ur_sim started twice over, two glue runs of 25 s of robot time each
def test_one_part_corrected_and_not(tmp_path, monkeypatch) -> None:
    out = tmp_path / 'parts'
    domain, lock = reserve_domain()  # the runner's processes on a domain of their own, not this process's
    try:
        monkeypatch.setenv('ROS_DOMAIN_ID', str(domain))
        code = main(['--parts', '1', '--seed', '3', '--jobs', '1', '--out', str(out)])
    finally:
        lock.close()
    summary = json.loads((out / 'summary.json').read_text())
    assert summary['parts'] == 1 and {'corrected', 'uncorrected'} <= set(summary)
    c, u = summary['corrected'], summary['uncorrected']
    for mode in (c, u):
        assert {'lateral_p95_mm', 'lateral_max_mm', 'gaps', 'width_within_5pct', 'refused'} <= set(mode)
    part = summary['generated'][0]
    assert max(abs(x) for x in part['offset_mm']) > 1.0  # a part that is off
    # measured: the offset found to a fraction of a millimetre in the fixture's plane
    found = part['measured']['offset_mm']
    assert all(abs(a - b) < 0.3 for a, b in zip(found[:2], part['offset_mm'][:2]))
    # corrected, the bead lands on its line; uncorrected it is off by millimetres
    assert c['refused'] == 0 and c['lateral_p95_mm'] < 0.5 and u['lateral_p95_mm'] > 1.0
    run = c['per_part'][0]
    # paced, the gun switched where planned: no gap, the loop closed within a few millimetres, the width held
    assert run['error_code'] == 0 and run['gaps'] == 0 and abs(run['closure_overlap_mm']) < 5.0
    assert run['width_within_5pct'] >= 0.97
    assert code == 0
    assert (out / 'index.html').is_file() and (out / 'lateral_p95_mm.png').is_file()
    log = (out / 'part_000' / 'run.log').read_text()
    assert log.count('bead:') == 2
    # paced, the bead's start is stamped without a margin for the delivery (ur_sim waits before it for the goal)
    aheads = [float(line.split('stamped ')[1].split(' s')[0]) for line in log.splitlines() if 'start stamped' in line]
    assert len(aheads) == 2 and max(aheads) < 1.0, aheads
    # each run recorded as a bag (read with mcap, not rosbags which wrote it): the arm's states, the scan, the bead
    for mode in ('corrected', 'uncorrected'):
        with open(out / 'part_000' / f'bag_{mode}' / f'bag_{mode}.mcap', 'rb') as f:
            summary = make_reader(f).get_summary()
        counts = {summary.channels[i].topic: n for i, n in summary.statistics.channel_message_counts.items()}
        assert counts['/joint_states'] > 1000 and counts['/ur_sim/part_scan'] > 10, counts
        assert counts['/ur_sim/glue_bead'] >= 1 and counts['/tf_static'] >= 1, counts


def test_a_paced_simulation_waits_for_its_client() -> None:
    with running_sim(lockstep=False, ur_type='ur5', initial_positions=HOME, pace_topic='/pace', pace_lag=0.02) as h:
        dt, lag = h.sim.sim.control_dt, 0.02
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        pace = h.client.create_publisher(Clock, '/pace', latched)
        # Until the client's first word the simulation runs at real time's pace; a hold in the past stops it.
        pace.publish(Clock(clock=_time(0.0)))
        wait_for(lambda: h.sim.pace.paced_until == 0.0, what='the hold at ur_sim')
        stopped = h.sim.sim.time
        for hold in (stopped + 0.5, stopped + 1.25):
            pace.publish(Clock(clock=_time(hold)))
            wait_for(lambda: h.sim.sim.time >= hold, what=f'the simulation at {hold:.3f} s')  # noqa: B023
            # and no further than the client allows (the newest cycle published within pace_lag of it; the
            # simulated time is one cycle past that cycle's stamp), however long it is left alone
            limit = hold + lag + 2 * dt + 1e-9
            assert h.sim.sim.time <= limit
            # an answer that takes no cycle (set_io): the simulation still holds meanwhile
            request = SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=3, state=float(hold > stopped + 1.0))
            assert call(h, SetIO, f'{IO}/set_io', request).success
            assert h.sim.sim.time <= limit


def _time(t: float):
    from builtin_interfaces.msg import Time

    return Time(sec=int(t), nanosec=int(round((t - int(t)) * 1e9)))
