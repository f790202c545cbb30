"""The simulated dispenser over DDS: set_io switches it, the bead grows on the windshield where the nozzle
axis meets the glass, /ur_sim/clear_glue_bead empties it; and the bead drawn in a MuJoCo render."""
from __future__ import annotations

import math

import mujoco
import numpy as np
from action_msgs.msg import GoalStatus
from sensor_msgs.msg import PointCloud2
from sim_harness import point, running_sim, wait_for
from std_srvs.srv import Trigger
from test_io_and_status import IO, Latest, call, client_for
from ur_msgs.msg import IOStates
from ur_msgs.srv import SetIO

from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rotation_from_zyx_euler
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD
from ur_sim_driver.description.bead import BASE_IN_WORLD, draw_bead, from_cloud, section
from ur_sim_driver.robot.dispenser import IDLE_FLOW, DispenserParams

HOME = np.array([0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0])
TIP_R = rotation_from_zyx_euler(0.0, 0.0, -math.pi / 3)  # seed 1's tip orientation
AXIS = TIP_R @ np.array([0.0, 1.0, 0.0])  # the nozzle axis (tool0's z) in the world
# Along the glass's lower edge, between two of seed 1's waypoints (world frame, m).
A, B = np.array([0.1021, 0.4186, 0.1449]), np.array([-0.0568, 0.4185, 0.1441])
STANDOFF = 0.004  # [m] tip above the glass along the nozzle axis
PIN = 16
P = DispenserParams()


def tip_target(s: float, standoff: float) -> np.ndarray:
    _, foot, _ = DEFAULT_WINDSHIELD.project((1.0 - s) * A + s * B)
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = TIP_R, foot[0] - standoff * AXIS
    return t


def joint_path(kin) -> tuple[np.ndarray, list[np.ndarray]]:
    above = kin.ik_or_raise(tip_target(0.0, 0.05), HOME, 'above the bead start')
    line, q = [], above
    for s in np.linspace(0.0, 1.0, 6):
        q = kin.ik_or_raise(tip_target(s, STANDOFF), q, f'bead point {s:.1f}')
        line.append(q)
    return above, line


def world(points_base: np.ndarray) -> np.ndarray:
    return points_base @ BASE_IN_WORLD[:3, :3].T


def set_pin(h, state: float, io: Latest) -> tuple[float, float, float]:
    """set_io on the dispenser's pin. Returns the simulated times before the call, of its answer and of the
    arrival of the first io_states showing the change."""
    before = h.sim.sim.time
    request = SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=PIN, state=state)
    future = client_for(h, SetIO, f'{IO}/set_io').call_async(request)
    answered = []
    future.add_done_callback(lambda _: answered.append(h.sim.sim.time))
    wait_for(lambda: answered, what='the set_io answer')
    assert future.result().success
    on = state != 0.0

    def seen() -> list[float]:
        return [t for m, t in list(io.items) if m.digital_out_states[PIN].state == on and t >= before]

    wait_for(seen, what=f'digital output {PIN} = {on} in io_states')
    return before, answered[0], min(seen())


def test_bead_is_laid_on_the_glass_where_the_nozzle_points() -> None:
    kin = ur_kinematics('ur5')
    above, line = joint_path(kin)
    with running_sim(ur_type='ur5', tool='dispenser', scene='windshield', initial_positions=HOME.tolist(),
                     real_time_factor=1.0) as h:
        dt = h.sim.sim.control_dt
        io, beads = Latest(h), Latest(h)
        h.listen(IOStates, f'{IO}/io_states', io)
        h.listen(PointCloud2, '/ur_sim/glue_bead', beads, latched=True)
        wait_for(lambda: io.last is not None, what='io_states')
        # To the bead start: above it, then down along the nozzle axis.
        handle = h.send(h.goal([point(above, 3.0), point(line[0], 4.0)]))
        assert handle.accepted
        assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, 0)
        assert beads.last is None  # nothing dispensed yet

        before_on, answered_on, _ = set_pin(h, 1.0, io)
        wait_for(lambda: beads.last is not None and beads.last.width > 0, what='the first bead message')
        # The dispenser publishes in the cycle that sees the output change, stamped with it: within one
        # control cycle of the answer (io_states of that cycle shows it too: both read the same IO). The stamp
        # is the cycle's start; the simulated time read by the test may fall within that cycle's step.
        first = beads.items[0][0].header.stamp
        seen_on = h.sim.clock.sim_time(first)  # in real time the stamps count from the system clock
        assert before_on - dt <= seen_on <= answered_on + dt + 1e-9
        rec = h.record()
        handle = h.send(h.goal([point(q, 0.5 + 0.3 * k) for k, q in enumerate(line)]))
        assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, 0)
        before_off, _, seen_off = set_pin(h, 0.0, io)  # seen_off: when io_states showed it arrive (later)
        t_idle = seen_off + P.off_delay + P.time_constant * math.log(1.0 / IDLE_FLOW) + 2 * dt
        h.wait_sim_time(t_idle + 0.2 - h.sim.sim.time)
        rec = h.stop_recording()
        bead = from_cloud(beads.last)
        assert beads.last.header.frame_id == 'base'
        # The deposits' times are on the stamps' clock; as simulated time, to about 0.24 us (float64 near 1.8e9 s).
        times = bead.times - h.sim.clock.origin_ns * 1e-9
        eps = 1e-6

        # Material reaches the glass only after the on delay (from the cycle the output was seen on) ...
        # (the bead starts at the tip's place in the last cycle before the valve opened).
        assert seen_on + P.on_delay - dt - eps <= times[0] <= seen_on + P.on_delay + eps
        # ... and keeps coming after the off delay, until the flow has died away.
        assert times[-1] >= before_off + P.off_delay
        assert times[-1] <= t_idle

        # Every point lies on the glass (the analytic surface our mesh was made from) ...
        pts = world(bead.points)
        _, foot, _ = DEFAULT_WINDSHIELD.project(pts)
        assert np.max(np.linalg.norm(pts - foot, axis=1)) < 1e-3
        # ... where the nozzle axis met it: on the tip's axis line at the point's time.
        t_js, q_js, _ = rec.arrays()
        moving = (times >= t_js[0]) & (times <= t_js[-1])
        assert moving.sum() > 100
        for p, t in zip(pts[moving][::10], times[moving][::10]):
            q = np.array([np.interp(t, t_js, q_js[:, j]) for j in range(6)])
            tip = kin.fk(q)
            axis = tip[:3, :3] @ np.array([0.0, 1.0, 0.0])
            off = p - tip[:3, 3]
            assert np.linalg.norm(off - (off @ axis) * axis) < 1e-3  # within 1 mm of the axis
            assert 0.0 < off @ axis < 0.02  # in front of the nozzle, near the standoff
        # The track: from the bead start to its end along the glass edge.
        assert np.linalg.norm(pts[0] - tip_target(0.0, 0.0)[:3, 3]) < 0.005
        assert np.linalg.norm(pts[-1] - tip_target(1.0, 0.0)[:3, 3]) < 0.005
        assert bead.length() > 0.9 * np.linalg.norm(B - A)
        assert np.all(bead.widths > 0.0) and np.all(bead.widths < 0.05)
        # Where the tip moved with the flow steady, the section is flow / speed over the glass.
        ds = np.linalg.norm(pts[20:] - pts[:-20], axis=1)
        speed = ds / np.maximum(times[20:] - times[:-20], 1e-9)
        mid = slice(10, len(speed) + 10)
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))][mid]
        # Away from the blobs the tip piles up where it stands at the start and the end.
        steady = (times[mid] > seen_on + P.on_delay + 5 * P.time_constant) & (speed > 0.05) & \
            (arc > 0.03) & (arc < arc[-1] - 0.03)
        assert steady.sum() > 50
        expected, _ = section(P.rate / speed[steady])
        np.testing.assert_allclose(bead.widths[mid][steady], expected, rtol=0.1)
        print(f'bead: {len(bead)} points, {bead.length():.3f} m, widths {bead.widths.min() * 1e3:.2f}-'
              f'{bead.widths.max() * 1e3:.2f} mm, steady {np.median(bead.widths[mid][steady]) * 1e3:.2f} mm at '
              f'{np.median(speed[steady]):.3f} m/s; times {times[0]:.3f}-{times[-1]:.3f} s; on seen '
              f'{seen_on:.3f} s, off seen {seen_off:.3f} s')

        # A render of the simulated model with the bead drawn shows it.
        image = render_with_bead(h, bead)
        r, g, b = (image[..., k].astype(int) for k in range(3))
        assert np.count_nonzero((r > 150) & (b > 150) & (g < 80)) > 50

        res = call(h, Trigger, '/ur_sim/clear_glue_bead', Trigger.Request())
        assert res.success and 'cleared' in res.message
        wait_for(lambda: beads.last.width == 0, what='the empty bead')


def render_with_bead(h, bead) -> np.ndarray:
    physics = h.sim.sim.physics
    with h.sim.host.lock:
        model, data = physics.model, mujoco.MjData(physics.model)
        data.qpos[:] = physics.data.qpos
    mujoco.mj_forward(model, data)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, 'base')
    world_from_base = np.eye(4)
    world_from_base[:3, :3], world_from_base[:3, 3] = data.xmat[base].reshape(3, 3), data.xpos[base]
    camera = mujoco.MjvCamera()
    camera.lookat[:] = world(bead.points).mean(axis=0)
    camera.distance, camera.azimuth, camera.elevation = 0.5, 90.0, -60.0
    with mujoco.Renderer(model, 240, 320) as renderer:
        renderer.update_scene(data, camera)
        n = renderer.scene.ngeom
        assert draw_bead(renderer.scene, bead, (1.0, 0.0, 1.0, 1.0), world_from_base) > 0
        assert renderer.scene.ngeom > n
        return renderer.render()
