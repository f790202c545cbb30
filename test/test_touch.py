"""The touch move: straight along the tool axis, through the surface point, at the requested peak speed."""
import numpy as np

from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.touch import touch_move
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import tool_axis


def test_the_tip_crosses_the_surface_point_on_the_tool_axis_at_the_peak_speed():
    job = load_job(default_job_path())
    plan = plan_job(job, np.array(job.home))
    kin = ur_kinematics(job.ur_type, job.tool)
    q_surface = plan.bead.q[0]
    axis = tool_axis(job.tool)
    seg = touch_move(kin, q_surface, axis, height=0.02, depth=0.02, speed=0.15, dt=job.sample_time)
    surface = kin.fk(q_surface)
    u = surface[:3, :3] @ (axis / np.linalg.norm(axis))
    tips = np.array([kin.fk(q)[:3, 3] for q in seg.q])
    along = (tips - surface[:3, 3]) @ u
    across = tips - surface[:3, 3] - np.outer(along, u)
    assert np.isclose(along[0], -0.02, atol=1e-6) and np.isclose(along[-1], 0.02, atol=1e-6)
    assert np.abs(across).max() < 1e-6
    speed = np.abs(np.diff(along)) / np.diff(seg.times)
    assert 0.145 < speed.max() <= 0.1501
    # the fastest sample is where the tip crosses the surface
    k = int(np.argmax(speed))
    assert abs(along[k]) < 0.002
