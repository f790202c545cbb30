"""The robot drawn in the page: link shapes and link poses from a URDF."""
import numpy as np

from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.studio.robot_geometry import RobotModel, shapes_for, tip_frame_of, ur_shapes, urdf_shapes
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf


def test_ur_shapes_cover_the_arm_and_the_tool():
    links = {s.link for s in ur_shapes(load_ur_params('ur5'), get_tool('dispenser'))}
    assert {'shoulder_link', 'upper_arm_link', 'forearm_link', 'wrist_3_link', 'dispenser', 'dispenser_tip'} <= links
    assert 'dispenser' not in {s.link for s in ur_shapes(load_ur_params('ur5'), None)}


def test_link_poses_agree_with_the_planner_kinematics():
    urdf = build_urdf(load_ur_params('ur10e'), tool=get_tool('dispenser'))
    robot = RobotModel(urdf)
    assert robot.joint_names == joint_names()
    kin = ur_kinematics('ur10e', 'dispenser')
    q = np.array([0.3, -1.2, 1.4, -0.5, 0.9, 0.2])
    assert np.allclose(robot.frame_position('dispenser_tip', joint_names(), q), kin.fk(q)[:3, 3], atol=1e-12)
    poses = robot.link_poses(list(reversed(joint_names())), q[::-1])  # joints are matched by name
    assert np.allclose(poses['dispenser_tip'][:3, 3], kin.fk(q)[:3, 3], atol=1e-12)
    assert robot.frame_position('nowhere', joint_names(), q) is None


def test_our_urdfs_use_the_simulator_shapes_and_others_their_own():
    ours = build_urdf(load_ur_params('ur5'), tf_prefix='left_', tool=get_tool('dispenser'))
    assert {s.link for s in shapes_for(ours)} >= {'left_forearm_link', 'left_dispenser'}
    other = """<robot name="arm"><link name="base"><visual><geometry><box size="0.2 0.2 0.1"/></geometry></visual>
      </link><link name="l1"/><link name="l2"/>
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
        <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.4 0 0"/>
        <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint></robot>"""
    shapes = urdf_shapes(other)
    assert [s.link for s in shapes] == ['base', 'l1']  # the box; a rod from l1 to l2 (base has a visual)
    assert np.allclose(shapes[0].mesh.extents, [0.2, 0.2, 0.1])
    assert np.isclose(shapes[1].mesh.extents.max(), 0.4, atol=1e-9)
    robot = RobotModel(other)
    assert np.allclose(robot.link_poses(['j1'], [np.pi / 2])['l1'][:3, 3], [0.0, 0.0, 0.3])


def test_seed_2_robot_mounted_1_m_up_is_drawn_there():
    base = np.eye(4)
    base[2, 3] = 1.0
    urdf = build_urdf(load_ur_params('ur10'), base_pose=base)  # as ur_sim publishes it for config/seed_ur10.yaml
    robot = RobotModel(urdf)
    assert {s.link for s in robot.shapes} >= {'shoulder_link', 'wrist_3_link'}
    poses = robot.link_poses(joint_names(), np.zeros(6))
    assert poses['base_link_inertia'][2, 3] == 1.0
    kin = ur_kinematics('ur10', None, frame='wrist_3_link', base_pose=base)
    assert np.allclose(poses['wrist_3_link'], kin.fk(np.zeros(6)), atol=1e-12)


def test_the_traced_tip_is_the_tool_tip_of_the_robot_description():
    dispenser = get_tool('dispenser')
    assert tip_frame_of(build_urdf(load_ur_params('ur5'), tool=dispenser)) == 'dispenser_tip'
    assert tip_frame_of(build_urdf(load_ur_params('ur10e'), tf_prefix='left_', tool=dispenser)) == 'left_dispenser_tip'
    assert tip_frame_of(build_urdf(load_ur_params('ur5'))) == 'tool0'  # no tool: the flange
    chain = """<robot name="arm"><link name="base"/><link name="l1"/><link name="l2"/>
      <joint name="j1" type="fixed"><parent link="base"/><child link="l1"/></joint>
      <joint name="j2" type="fixed"><parent link="l1"/><child link="l2"/></joint></robot>"""
    assert tip_frame_of(chain) == 'l2'  # another robot: the end of its chain
