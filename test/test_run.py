"""The pure parts of running a plan (execution/run.py): the bead's delivery margin and the result messages."""
import pytest

from ur_glue_planner.execution.client import GoalOutcome
from ur_glue_planner.execution.run import BEAD_DELIVERY, DELIVERY_FACTOR, MESSAGES, bead_delivery, describe


def test_bead_delivery_is_the_floor_on_a_quick_machine():
    assert bead_delivery([]) == BEAD_DELIVERY
    assert bead_delivery([0.004, 0.02]) == BEAD_DELIVERY


def test_bead_delivery_grows_with_the_slowest_answer_seen():
    # Four jobs sharing two cores answered goals in about 0.4 s; a 1 s margin let the bead's goal arrive
    # after its own start (the controller then samples past the start: PATH_TOLERANCE_VIOLATED).
    assert bead_delivery([0.05, 0.6, 0.2]) == pytest.approx(DELIVERY_FACTOR * 0.6)
    assert bead_delivery([0.6]) > BEAD_DELIVERY


@pytest.mark.parametrize('code', sorted(MESSAGES))
def test_every_result_code_is_described_with_the_servers_text(code):
    text = describe(GoalOutcome(code, 'server says so', 'aborted'))
    assert text.startswith(MESSAGES[code]) and f'error_code {code}' in text and text.endswith('server says so')


def test_an_unknown_code_is_named_unknown():
    assert describe(GoalOutcome(-42, '', 'aborted')).startswith('unknown error code (error_code -42')
