"""The wait before the bead of a studio run: from the delivery of earlier beads, not extrapolated from short goals."""
import pytest

from ur_glue_planner.execution.client import DELIVERY_FACTOR, delivery_margin
from ur_glue_planner.execution.run import BEAD_DELIVERY
from ur_glue_planner.studio.run_client import BEAD_SHARE, RECENT, bead_margin

BEAD = 792  # points of the seed's bead goal; approach 201, descent 95


def test_the_first_run_extrapolates_as_the_planner_does():
    answers = [(0.076, 201), (0.009, 95)]
    assert bead_margin(answers, BEAD_DELIVERY, BEAD) == delivery_margin(answers, BEAD_DELIVERY, BEAD)


def test_later_runs_take_the_earlier_beads_delivery_not_a_short_goals_hiccup():
    # Seen in the studio with a browser open: a 95-point descent answered in 178 ms, scaled to the bead's 792
    # points and x4 made the bead wait 5.95 s; the bead goals themselves were answered in 10 to 55 ms.
    answers = [(0.076, 201), (0.009, 95), (0.010, BEAD), (0.09, 95),  # run 1
               (0.007, 201), (0.178, 95)]  # run 2 so far
    assert delivery_margin(answers, BEAD_DELIVERY, BEAD) == pytest.approx(DELIVERY_FACTOR * 0.178 * BEAD / 95)
    assert bead_margin(answers, BEAD_DELIVERY, BEAD) == BEAD_DELIVERY  # 4 x 10 ms is below the floor
    slow = answers + [(0.4, BEAD)]  # a loaded machine's slow bead delivery still counts
    assert bead_margin(slow, BEAD_DELIVERY, BEAD) == pytest.approx(DELIVERY_FACTOR * 0.4)


def test_only_the_recent_beads_count():
    answers = [(0.6, BEAD)] + [(0.02, BEAD)] * RECENT
    assert bead_margin(answers, BEAD_DELIVERY, BEAD) == BEAD_DELIVERY


def test_a_slightly_longer_bead_takes_the_earlier_beads_delivery():
    # A measured part's bead has a few points more than the nominal one before it: the earlier beads still say how
    # long a bead takes to deliver (only beads of at least as many points counted, and the wait went 1.1 -> 5.7 s).
    answers = [(0.076, 201), (0.009, 95), (0.010, BEAD), (0.09, 95),  # run 1, nominal part
               (0.007, 201), (0.178, 95)]  # run 2 so far, on a measured part
    longer = BEAD + 8
    assert bead_margin(answers, BEAD_DELIVERY, longer) == BEAD_DELIVERY  # 4 x 10 ms x 800 / 792 is below the floor
    slow = answers[:2] + [(0.4, BEAD)] + answers[3:]  # a slow bead delivery counts, scaled to the longer bead
    assert bead_margin(slow, BEAD_DELIVERY, longer) == pytest.approx(DELIVERY_FACTOR * 0.4 * longer / BEAD)


def test_a_short_goal_is_not_taken_for_a_bead():
    # The approach (201 points) is under BEAD_SHARE of the bead: without an earlier bead, the planner's rule holds.
    answers = [(0.076, 201), (0.009, 95)]
    assert 201 < BEAD_SHARE * BEAD
    assert bead_margin(answers, BEAD_DELIVERY, BEAD) == delivery_margin(answers, BEAD_DELIVERY, BEAD)
