"""The pure parts of running a plan (execution/run.py and the client's delivery margin): the bead's delivery
margin and the result messages."""
import pytest

from ur_glue_planner.execution.client import DELIVERY_FACTOR, delivery_margin
from ur_glue_planner.execution.run import BEAD_DELIVERY, MESSAGES, describe
from ur_glue_planner.execution.trajectory_goal import GoalOutcome


def bead_delivery(answers, points):
    return delivery_margin(answers, BEAD_DELIVERY, points)


def test_bead_delivery_is_the_floor_on_a_quick_machine():
    assert bead_delivery([], 792) == BEAD_DELIVERY
    assert bead_delivery([(0.004, 201), (0.02, 95)], 792) == BEAD_DELIVERY


def test_bead_delivery_grows_with_the_slowest_answer_seen_scaled_to_the_beads_length():
    # Four jobs sharing two cores answered a 201-point goal in about 0.3 s; the 792-point bead took longer to
    # deliver than a margin of 4 x 0.3 s, arrived after its own start and aborted (PATH_TOLERANCE_VIOLATED).
    assert bead_delivery([(0.3, 201), (0.05, 95)], 792) == pytest.approx(DELIVERY_FACTOR * 0.3 * 792 / 201)
    assert bead_delivery([(0.6, 792)], 792) == pytest.approx(DELIVERY_FACTOR * 0.6)
    assert bead_delivery([(0.6, 1000)], 792) == pytest.approx(DELIVERY_FACTOR * 0.6)  # never scaled down


@pytest.mark.parametrize('code', sorted(MESSAGES))
def test_every_result_code_is_described_with_the_servers_text(code):
    text = describe(GoalOutcome(code, 'server says so', 'aborted'))
    assert text.startswith(MESSAGES[code]) and f'error_code {code}' in text and text.endswith('server says so')


def test_an_unknown_code_is_named_unknown():
    assert describe(GoalOutcome(-42, '', 'aborted')).startswith('unknown error code (error_code -42')
