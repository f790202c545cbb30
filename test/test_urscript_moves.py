"""The profiles of URScript's moves (pure): a trapezoid within its acceleration and speed, a given time kept, a
joint move arriving with all joints together, a tool move on its straight line."""
import numpy as np
import pytest

from ur_sim_driver.description.analytic_ik import UrAnalyticIK
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.moves import Arc, JointLine, Speed, ToolLine, Trapezoid

DT = 0.002
P = load_ur_params('ur5e')
IK = UrAnalyticIK(P.dh, base_pose=np.diag([-1.0, -1.0, 1.0, 1.0]))
Q0 = np.array([0.0, -1.2, 1.2, -1.57, -1.57, 0.0])


@pytest.mark.parametrize('distance, a, v, t', [(0.5, 1.4, 1.05, 0.0), (3.0, 1.4, 1.05, 0.0), (0.5, 1.4, 1.05, 2.0),
                                               (0.5, 0.1, 1.0, 1.0)])
def test_a_trapezoid_covers_its_way_within_its_limits(distance, a, v, t):
    profile = Trapezoid.build(distance, a, v, t)
    times = np.arange(0.0, profile.duration + DT, DT / 4)
    s, sd, sdd = np.array([profile.sample(ti) for ti in times]).T
    assert s[0] == 0.0 and s[-1] == pytest.approx(distance, abs=1e-12) and sd[-1] == 0.0
    assert np.all(np.diff(s) >= -1e-12)
    if t > 0.0:
        assert profile.duration == pytest.approx(t)
    else:
        assert sd.max() <= v + 1e-12 and np.abs(sdd).max() <= a + 1e-12
        # the fastest such profile: it reaches v when the way allows, else a triangle
        expected = distance / v + v / a if distance >= v * v / a else 2.0 * np.sqrt(distance / a)
        assert profile.duration == pytest.approx(expected)
    # the speed is the way's derivative (the trapezoid rule errs by up to a * step where a step spans a corner)
    assert np.allclose(np.diff(s) / np.diff(times), (sd[1:] + sd[:-1]) / 2, atol=profile.accel * DT / 4)


def test_a_joint_move_brings_every_joint_in_together_on_a_line():
    q1 = Q0 + np.array([0.5, -0.25, 0.1, 0.0, 0.3, -0.5])
    move = JointLine(Q0, q1, a=1.4, v=1.05)
    for t in np.linspace(0.0, move.duration, 50):
        q, qd, _ = move.sample(t)
        s = (q - Q0)[0] / 0.5
        assert np.allclose(q, Q0 + s * (q1 - Q0), atol=1e-12)  # on the line in joint space
        assert np.abs(qd).max() <= 1.05 + 1e-12
    assert np.array_equal(move.sample(move.duration)[0], q1)


def test_a_tool_move_keeps_the_tool_on_its_straight_line_and_turns_it_evenly():
    t0 = IK.fk(Q0)
    t1 = t0.copy()
    t1[:3, 3] += [0.1, -0.05, 0.08]
    move = ToolLine(IK, Q0, t0, t1, a=1.2, v=0.25, t=0.0, dt=DT, q_min=P.q_min, q_max=P.q_max)
    assert move.duration == pytest.approx(Trapezoid.build(float(np.linalg.norm([0.1, -0.05, 0.08])), 1.2, 0.25)
                                          .duration)
    for t in np.linspace(0.0, move.duration, 40):
        pose = IK.fk(move.sample(t)[0])
        offset = pose[:3, 3] - t0[:3, 3]
        direction = (t1[:3, 3] - t0[:3, 3]) / np.linalg.norm(t1[:3, 3] - t0[:3, 3])
        assert np.linalg.norm(offset - offset @ direction * direction) < 1e-4  # on the line, to the grid's error
        assert np.allclose(pose[:3, :3], t0[:3, :3], atol=1e-6)
    assert np.allclose(IK.fk(move.sample(move.duration)[0]), t1, atol=1e-9)


def test_a_tool_move_out_of_reach_is_refused_before_it_starts():
    t1 = IK.fk(Q0)
    t1[:3, 3] += [3.0, 0.0, 0.0]
    with pytest.raises(ScriptError, match='movel: the pose at .* of the way is out of reach'):
        ToolLine(IK, Q0, IK.fk(Q0), t1, a=1.2, v=0.25, t=0.0, dt=DT, q_min=P.q_min, q_max=P.q_max)


def test_speed_ramps_with_its_acceleration_and_holds():
    move = Speed(Q0, np.zeros(6), np.array([0.2, -0.1, 0, 0, 0, 0]), a=1.0, t=0.5)
    assert move.ramp == pytest.approx(0.2) and move.returns_after == 0.5 and np.isinf(move.duration)
    q, qd, _ = move.sample(1.2)
    assert np.allclose(qd, [0.2, -0.1, 0, 0, 0, 0]) and q[0] == pytest.approx(0.5 * 0.2 * 0.2 + 0.2 * 1.0)
    stop = Speed(q, qd, np.zeros(6), a=2.0, t=None)
    assert stop.duration == pytest.approx(0.1) and np.allclose(stop.sample(0.1)[1], 0.0)


def test_an_arc_through_three_points_and_a_movec_along_it():
    p0, via, p1 = np.array([0.3, 0.0, 0.2]), np.array([0.4, 0.1, 0.2]), np.array([0.5, 0.0, 0.2])
    arc = Arc.through(p0, via, p1)
    assert arc.radius == pytest.approx(0.1) and np.allclose(arc.centre, [0.4, 0.0, 0.2])
    assert arc.angle == pytest.approx(np.pi)  # half a circle, through the via point
    points = arc.position(np.linspace(0.0, 1.0, 9))
    assert np.allclose(points[0], p0) and np.allclose(points[4], via) and np.allclose(points[-1], p1)
    with pytest.raises(ScriptError, match='lie on a line'):
        Arc.through(p0, (p0 + p1) / 2, p1)
    # movec from the arm's pose: a quarter circle of radius 5 cm in the base's x-y plane, orientation kept
    t0 = IK.fk(Q0)
    start = t0[:3, 3]
    centre = start + [0.05, 0.0, 0.0]
    t_via, t1 = t0.copy(), t0.copy()
    t_via[:3, 3] = centre + 0.05 * np.array([-np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0])
    t1[:3, 3] = centre + [0.0, 0.05, 0.0]
    arc = Arc.through(start, t_via[:3, 3], t1[:3, 3])
    move = ToolLine(IK, Q0, t0, t1, 1.2, 0.1, 0.0, DT, P.q_min, P.q_max, arc=arc, name='movec')
    tcp = IK.fk(move.q)[:, :3, 3]
    assert np.allclose(np.linalg.norm(tcp - centre, axis=1), 0.05, atol=1e-6)
    assert np.allclose(tcp[-1], t1[:3, 3], atol=1e-6)
    assert move.duration == pytest.approx(0.05 * np.pi / 2 / 0.1 + 0.1 / 1.2, rel=1e-6)  # way / v + v / a
