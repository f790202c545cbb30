"""Execution: the ROS boundary: the client API, running a plan through FollowJointTrajectory, the planner node."""
