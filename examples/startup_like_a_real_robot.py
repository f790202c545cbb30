"""Start up a UR like on the real robot, then move, switch the glue gun and read the wrench.

Plain rclpy against the UR ROS 2 driver's interfaces, so the same script runs against ur_sim and a real robot
(headless mode, or with the External Control program loaded). Run the simulator powered off first:

    ur_sim --ros-args -p start_powered_off:=true -p tool:=dispenser
    python examples/startup_like_a_real_robot.py            # --gun-pin 16 (tool output 0 is pin 16)

Steps: power on, wait for IDLE; release the brakes, wait for RUNNING; play the program, wait for
robot_program_running; move wrist_3 by 0.3 rad and back; switch the gun output on, then off, each confirmed on
io_states; read the wrench (the tool's weight at rest). Every wait has a deadline and says what it waited for.
"""
from __future__ import annotations

import argparse
import sys
import time

import rclpy
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from geometry_msgs.msg import WrenchStamped
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectoryPoint
from ur_dashboard_msgs.msg import RobotMode
from ur_msgs.msg import IOStates
from ur_msgs.srv import SetIO

TIMEOUT = 20.0  # [s] wall-clock deadline of every wait


class Robot:
    """The interfaces this script uses, on one node, spun from this thread only."""

    def __init__(self, node: Node) -> None:
        self.node = node
        self.latest: dict[str, object] = {}
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        io = '/io_and_status_controller'
        for msg_type, topic, qos in ((RobotMode, f'{io}/robot_mode', latched),
                                     (Bool, f'{io}/robot_program_running', latched),
                                     (IOStates, f'{io}/io_states', 10), (JointState, '/joint_states', 10),
                                     (WrenchStamped, '/force_torque_sensor_broadcaster/wrench', 10)):
            node.create_subscription(msg_type, topic, lambda m, t=topic: self.latest.__setitem__(t, m), qos)
        self.set_io = node.create_client(SetIO, f'{io}/set_io')
        self.action = ActionClient(node, FollowJointTrajectory,
                                   '/scaled_joint_trajectory_controller/follow_joint_trajectory')
        self.executor = SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)

    def wait(self, what: str, condition) -> None:
        deadline = time.monotonic() + TIMEOUT
        while not condition():
            if time.monotonic() > deadline:
                raise TimeoutError(f'no {what} within {TIMEOUT:.0f} s')
            self.executor.spin_once(timeout_sec=0.05)

    def call(self, client, request):
        self.wait(f'{client.srv_name} service', client.service_is_ready)
        future = client.call_async(request)
        self.wait(f'answer from {client.srv_name}', future.done)
        return future.result()

    def dashboard(self, command: str) -> str:
        answer = self.call(self.node.create_client(Trigger, f'/dashboard_client/{command}'), Trigger.Request())
        print(f'dashboard {command}: {answer.message!r}')
        if not answer.success:
            raise RuntimeError(f'dashboard {command} failed: {answer.message}')
        return answer.message

    def topic(self, name: str):
        return self.latest.get(name)


def robot_mode(robot: Robot) -> int | None:
    msg = robot.topic('/io_and_status_controller/robot_mode')
    return None if msg is None else msg.mode


def run(node: Node, gun_pin: int = 16) -> dict:
    """Run every step on `node` (spun here); returns what was observed."""
    robot = Robot(node)
    robot.wait('robot_mode', lambda: robot_mode(robot) is not None)
    if robot_mode(robot) != RobotMode.RUNNING:
        robot.dashboard('power_on')
        robot.wait('robot mode IDLE', lambda: robot_mode(robot) == RobotMode.IDLE)
        robot.dashboard('brake_release')
        robot.wait('robot mode RUNNING', lambda: robot_mode(robot) == RobotMode.RUNNING)
    program = robot.topic('/io_and_status_controller/robot_program_running')
    if program is None or not program.data:
        robot.dashboard('play')
    robot.wait('robot_program_running', lambda: (m := robot.topic('/io_and_status_controller/robot_program_running'))
               is not None and m.data)

    robot.wait('joint_states', lambda: robot.topic('/joint_states') is not None)
    js = robot.topic('/joint_states')
    q0 = list(js.position)
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = list(js.name)
    moved = q0[:5] + [q0[5] + 0.3]
    goal.trajectory.points = [JointTrajectoryPoint(positions=moved, time_from_start=Duration(sec=2)),
                              JointTrajectoryPoint(positions=q0, time_from_start=Duration(sec=4))]
    robot.wait('the trajectory action server', robot.action.server_is_ready)
    # The driver's controller_stopper activates the trajectory controller again just after the program plays;
    # a goal sent in that moment is rejected, so it is sent again for a little while.
    deadline = time.monotonic() + 2.0
    while True:
        sent = robot.action.send_goal_async(goal)
        robot.wait('the goal response', sent.done)
        if sent.result().accepted:
            break
        if time.monotonic() > deadline:
            raise RuntimeError('the trajectory goal was rejected')
        robot.executor.spin_once(timeout_sec=0.1)
    result = sent.result().get_result_async()
    robot.wait('the trajectory result', result.done)
    error_code = result.result().result.error_code
    print(f'trajectory: error_code {error_code} {result.result().result.error_string!r}')

    gun = []
    for state in (1.0, 0.0):
        answer = robot.call(robot.set_io, SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=gun_pin,
                                                        state=state))
        if not answer.success:
            raise RuntimeError(f'set_io pin {gun_pin} state {state} failed')
        robot.wait(f'digital output {gun_pin} = {bool(state)}',
                   lambda s=state: (m := robot.topic('/io_and_status_controller/io_states')) is not None
                   and m.digital_out_states[gun_pin].state == bool(s))
        gun.append(bool(state))
        print(f'glue gun (output {gun_pin}): {"on" if state else "off"}')

    robot.wait('a wrench', lambda: robot.topic('/force_torque_sensor_broadcaster/wrench') is not None)
    w = robot.topic('/force_torque_sensor_broadcaster/wrench').wrench
    force = (w.force.x, w.force.y, w.force.z)
    print(f'wrench in {robot.topic("/force_torque_sensor_broadcaster/wrench").header.frame_id}: '
          f'force {tuple(round(f, 2) for f in force)} N')
    return {'error_code': error_code, 'gun': gun, 'force': force, 'robot_mode': robot_mode(robot)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--gun-pin', type=int, default=16, help='digital output of the glue gun (16, 17: tool)')
    args = parser.parse_args()
    rclpy.init()
    node = Node('startup_example')
    try:
        run(node, args.gun_pin)
        return 0
    except (TimeoutError, RuntimeError) as exc:
        print(f'startup example: {exc}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    sys.exit(main())
