"""Compiled MjData readout equals MuJoCo's own routines and numpy indexing, including non-contiguous indices."""
import mujoco
import numpy as np

from ur_sim_driver.physics.mj_readout import read_dynamics, read_joints

# A free box first (7 qpos, 6 dofs), then a chain of three hinges: joint addresses do not start at 0.
XML = """<mujoco><worldbody>
  <body name="box" pos="1 0 0"><freejoint/><geom type="box" size=".1 .1 .1" mass="2"/></body>
  <body name="base" pos="0 0 .5" euler="10 20 30"><geom type="sphere" size=".05" mass="1"/>
    <body name="l1"><joint name="j1" axis="0 0 1" damping="0.5"/><geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/>
      <body name="l2" pos=".3 0 0"><joint name="j2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/>
        <body name="l3" pos=".3 0 0"><joint name="j3" axis="1 0 0"/><geom type="box" size=".02 .05 .02"/>
          <site name="tcp" pos=".05 .02 .01" euler="5 50 -40"/></body></body></body></body>
</worldbody>
<actuator><motor joint="j3"/><motor joint="j1"/><motor joint="j2"/></actuator></mujoco>"""


def _model():
    m = mujoco.MjModel.from_xml_string(XML)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(1)
    d.qpos[7:] = rng.uniform(-2, 2, 3)
    d.qvel[6:] = rng.uniform(-1, 1, 3)
    d.ctrl[:] = rng.uniform(-1, 1, 3)
    mujoco.mj_forward(m, d)
    return m, d


def _indices(m, order=('j2', 'j3', 'j1')):
    jids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in order]
    qpos = np.array([m.jnt_qposadr[j] for j in jids], dtype=np.int64)
    dof = np.array([m.jnt_dofadr[j] for j in jids], dtype=np.int64)
    act = np.array([next(a for a in range(m.nu) if m.actuator_trnid[a, 0] == j) for j in jids], dtype=np.int64)
    return qpos, dof, act


def test_joints_and_dynamics_are_read_at_their_addresses():
    m, d = _model()
    qpos, dof, act = _indices(m)
    out = np.empty((3, 3))
    read_joints(d.qpos, d.qvel, d.actuator_force, qpos, dof, act, out)
    assert np.array_equal(out, np.array([d.qpos[qpos], d.qvel[dof], d.actuator_force[act]]))
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    mass, bias = np.empty((3, 3)), np.empty(3)
    read_dynamics(full, d.qfrc_bias, d.qfrc_passive, dof, mass, bias)
    assert np.array_equal(mass, full[np.ix_(dof, dof)])
    assert np.array_equal(bias, d.qfrc_bias[dof] - d.qfrc_passive[dof])
    assert d.qfrc_passive[dof].any()  # the damped joint makes the passive term count
