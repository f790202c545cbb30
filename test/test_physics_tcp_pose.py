"""The TCP pose the simulation reports (MuJoCo's frame sensors) is tool0 in base by the URDF's kinematics."""
import numpy as np
import pinocchio as pin
import pytest

from ur_sim_driver.description.mjcf import (
    FT_FORCE_SENSOR,
    FT_TORQUE_SENSOR,
    PAYLOAD_BODY,
    TCP_ORIENTATION_SENSOR,
    TCP_POSITION_SENSOR,
    build_mjcf,
)
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf
from ur_sim_driver.physics.physics import ArmPhysics

pytestmark = pytest.mark.timeout(60)


@pytest.mark.parametrize('prefix', ['', 'left_'])
def test_tcp_pose_is_tool0_in_base_with_a_non_negative_w(prefix):
    params, tool = load_ur_params('ur10e'), get_tool('dispenser')
    physics = ArmPhysics(build_mjcf(params, tf_prefix=prefix, tool=tool), joint_names(prefix), 0.002, 4,
                         base_body=prefix + 'base', payload_body=prefix + PAYLOAD_BODY,
                         tcp_sensors=(prefix + TCP_POSITION_SENSOR, prefix + TCP_ORIENTATION_SENSOR),
                         ft_sensors=(prefix + FT_FORCE_SENSOR, prefix + FT_TORQUE_SENSOR))
    model = pin.buildModelFromXML(build_urdf(params, tf_prefix=prefix, tool=tool))
    data = model.createData()
    base, tool0 = model.getFrameId(prefix + 'base'), model.getFrameId(prefix + 'tool0')
    rng = np.random.default_rng(3)
    raw_negative_w = 0  # MuJoCo's own sign varies: the reported one must not
    for q in rng.uniform(-3.0, 3.0, (20, 6)):
        physics.reset(q)
        position, xyzw = physics.tcp_pose()
        pin.framesForwardKinematics(model, data, q)
        want = data.oMf[base].inverse() * data.oMf[tool0]
        np.testing.assert_allclose(position, want.translation, rtol=0, atol=1e-9)
        assert xyzw[3] >= 0.0 and abs(np.linalg.norm(xyzw) - 1.0) < 1e-12
        np.testing.assert_allclose(pin.Quaternion(xyzw[3], *xyzw[:3]).matrix(), want.rotation, rtol=0, atol=1e-9)
        raw_negative_w += physics.data.sensor(prefix + TCP_ORIENTATION_SENSOR).data[0] < 0.0
    assert raw_negative_w > 0
