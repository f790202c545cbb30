"""The trajectory controllers' FollowJointTrajectory actions and JointTrajectory topics, served by a second
process (``trajectory_gateway.py``) so that taking in a 100,000-point goal never stalls the simulation; the pipe
between the processes (``gateway_link.py``) and its wire format (``cdr.py``,
``trajectory_cdr.py``). May import urscript, motion, robot, physics and description."""
