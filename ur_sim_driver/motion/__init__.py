"""Trajectories without ROS: the command types, sampling (``trajectory.py``), tolerances, validation of a goal
against the driver's rules, the trajectory controller's core (``jtc.py``), the passthrough controller's rules and the
FollowJointTrajectory result codes. Numpy arrays and frozen dataclasses in and out; tested with plain pytest. No
rclpy: ``conversions.py`` maps ROS messages to these types and back. May import robot, physics and description."""
