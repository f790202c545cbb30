"""Goal order under load: bursts of back-to-back goals, random cancels; the newest accepted goal runs."""
from collections import defaultdict

import numpy as np
from action_msgs.msg import GoalStatus, GoalStatusArray
from sim_harness import point, running_sim, wait_for

from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.motion.jtc import PREEMPTED_BY_ACTION

TERMINAL = {GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED, GoalStatus.STATUS_CANCELED}
# 100 bursts of three with about 30 random cancels. Every goal stays in the server's status array until its result
# expires, so the cost grows with the square of the count: 1000 goals took 69 s on a quiet 2-core machine, 300 take
# 13 s, and the orders and races this checks all occur within the first hundred bursts.
GOALS = 300


def test_storm_of_bursts_and_cancels_keeps_the_newest_goal_running():
    rng = np.random.default_rng(9)
    terminal_seen: dict[bytes, set[int]] = defaultdict(set)  # every terminal status a goal ever showed
    latest: list[GoalStatusArray] = []

    def on_status(msg: GoalStatusArray) -> None:
        latest[:] = [msg]
        for s in msg.status_list:
            if s.status in TERMINAL:
                terminal_seen[bytes(s.goal_info.goal_id.uuid)].add(s.status)

    with running_sim() as h:
        ctrl = h.sim.cfg.controller_name
        # Depth 1: each array lists every goal, so the newest is all that counts; a deep queue of arrays that
        # grow to 1,000 goals would take this listener longer to read than the storm takes.
        h.listen(GoalStatusArray, f'/{ctrl}/follow_joint_trajectory/_action/status', on_status, depth=1)
        q0 = h.q
        results = {}  # goal id -> (status, code, text) from the result service
        previous_newest = None
        sent = 0
        while sent < GOALS:
            size = min(3, GOALS - sent)
            # Long, slow goals around the start: each would still run when the next one arrives.
            goals = [h.goal([point(q0 + rng.uniform(-0.05, 0.05, 6), 30.0, np.zeros(6))]) for _ in range(size)]
            futures = [h.action.send_goal_async(g) for g in goals]  # back to back, no waiting in between
            sent += size
            wait_for(lambda fs=futures: all(f.done() for f in fs), what='the burst to be accepted')
            handles = [f.result() for f in futures]
            assert all(hd.accepted for hd in handles)
            ids = [bytes(hd.goal_id.uuid) for hd in handles]
            result_futures = [hd.get_result_async() for hd in handles]
            newest = handles[-1]
            # The newest goal of the burst runs ...
            wait_for(lambda token=ids[-1]: h.sim.jtc.active_token == token, what='the newest goal to run')
            # ... and every older one (of this burst, and the previous burst's newest) ended preempted.
            older = list(zip(ids[:-1], result_futures[:-1]))
            if previous_newest is not None:
                older.append(previous_newest)
            for goal_id, future in older:
                wait_for(future.done, what='a preempted goal to end')
                r = future.result()
                results[goal_id] = (r.status, r.result.error_code, r.result.error_string)
                if r.status != GoalStatus.STATUS_CANCELED:
                    assert results[goal_id] == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL, PREEMPTED_BY_ACTION)
            previous_newest = (ids[-1], result_futures[-1])
            if rng.random() < 0.3:  # a random cancel of the running goal
                h.cancel(newest)
                wait_for(result_futures[-1].done, what='the canceled result')
                r = result_futures[-1].result()
                results[ids[-1]] = (r.status, r.result.error_code, r.result.error_string)
                assert r.status == GoalStatus.STATUS_CANCELED
                assert h.sim.jtc.active_token is None
                previous_newest = None
        last_id, last_future = previous_newest or (None, None)
        if last_future is not None:
            last = [hd for hd in handles if bytes(hd.goal_id.uuid) == last_id][0]
            h.cancel(last)
            wait_for(last_future.done, what='the last result')
            results[last_id] = (last_future.result().status, 0, '')
        assert len(results) == GOALS
        # Every goal got exactly one terminal status on the status topic, the one its result gave: the server's
        # latest status array lists them all, and no goal ever showed another terminal status.

        def final_statuses() -> dict[bytes, int]:
            return {bytes(s.goal_info.goal_id.uuid): s.status for s in latest[0].status_list} if latest else {}

        wait_for(lambda: all(final_statuses().get(g) in TERMINAL for g in results),
                 what='every goal in a terminal state on the status topic')
        final = final_statuses()
        for goal_id, (status, _, _) in results.items():
            assert final[goal_id] == status
            assert terminal_seen[goal_id] == {status}
