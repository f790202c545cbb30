"""Test-process set-up shared by every suite.

Each pytest process takes its own ROS_DOMAIN_ID (held by a file lock for the life of the process)
so that two test runs on one machine never see each other, keeps DDS discovery on localhost and
writes ROS logs into a temporary directory.
"""
from __future__ import annotations

import fcntl
import os
import sys
import tempfile
from pathlib import Path

import pytest

_DOMAIN_LOCK_DIR = Path(tempfile.gettempdir()) / 'ur_sim_driver_test_domains'
_held_lock = None  # keeps the lock file open (and the domain reserved) until the process exits


def _reserve_domain_id() -> int:
    """Take a free domain id in 1..101 that no other test process holds, for the life of this process."""
    global _held_lock
    domain, _held_lock = reserve_domain()
    return domain


def reserve_domain() -> tuple[int, object]:
    """A free domain id in 1..101 and its lock file: held until the file is closed (e.g. for processes a test
    starts, which then meet nothing of this process's)."""
    _DOMAIN_LOCK_DIR.mkdir(parents=True, exist_ok=True)
    # Start from the pid so that concurrent processes rarely contend for the same file.
    start = os.getpid() % 101
    for k in range(101):
        domain = 1 + (start + k) % 101
        f = open(_DOMAIN_LOCK_DIR / f'{domain}.lock', 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            continue
        return domain, f
    raise RuntimeError(f'no free ROS_DOMAIN_ID in 1..101 under {_DOMAIN_LOCK_DIR}')


def pytest_configure(config) -> None:
    # pytest-xdist's workers inherit the environment of the process that started them: each takes its own domain.
    if 'UR_SIM_TEST_DOMAIN_ID' not in os.environ or 'PYTEST_XDIST_WORKER' in os.environ:
        os.environ['UR_SIM_TEST_DOMAIN_ID'] = str(_reserve_domain_id())
    os.environ['ROS_DOMAIN_ID'] = os.environ['UR_SIM_TEST_DOMAIN_ID']
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    log_dir = Path(tempfile.mkdtemp(prefix='ur_sim_driver_roslog_'))
    os.environ['ROS_LOG_DIR'] = str(log_dir)
    os.environ.setdefault('MUJOCO_GL', 'egl')
    # As ur_sim's main() does: the in-process simulation thread needs the GIL handed over often.
    from ur_sim_driver.ros.main import GIL_SWITCH_INTERVAL
    sys.setswitchinterval(GIL_SWITCH_INTERVAL)
    # Helpers shared by the suites live beside this file.
    sys.path.insert(0, str(Path(__file__).resolve().parent))


# The modules that take longest (seconds of one worker, measured with `-n 3` on the 2-core machine, 2026-12-02;
# docs/testing.md), slowest first. `make test` hands whole modules to its workers in collection order
# (`--dist loadfile --no-loadscope-reorder`): started first, the longest ones no longer end the run alone on one
# worker while the others are idle. Modules not named here follow in their usual order; a stale entry costs only
# balance, never a result.
SLOWEST_FIRST = (
    'test_studio_browser', 'test_glue_bead_e2e', 'test_trajectory_intake', 'test_upstream_scenarios_force',
    'test_upstream_scenarios_motion', 'test_rtde_control', 'test_examples', 'test_ur_rtde_control',
    'test_studio_page_browser', 'test_tool_contact', 'test_planner_node', 'test_parts_run',
    'test_studio_live_browser', 'test_driver_scenarios', 'test_force_mode', 'test_upstream_scenarios_models',
    'test_executables', 'test_dashboard', 'test_node_params', 'test_upstream_scenarios',
)


def pytest_collection_modifyitems(config, items) -> None:
    rank = {name: k for k, name in enumerate(SLOWEST_FIRST)}
    # A stable sort: each module's tests keep their order.
    items.sort(key=lambda item: rank.get(Path(str(item.fspath)).stem, len(rank)))


def pytest_report_header(config) -> str:
    return f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID')} ROS_LOG_DIR={os.environ.get('ROS_LOG_DIR')}"


@pytest.fixture(autouse=True)
def robot_recovered():
    """After every test: each simulation still running (a module fixture's) brought back as a user would bring
    the robot back (``sim_harness.RobotKeeper``): safety, power, program and controllers."""
    yield
    from sim_harness import open_harnesses

    for harness in open_harnesses():
        harness.keeper.recover()
