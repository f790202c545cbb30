"""The trajectory controllers' FollowJointTrajectory actions and JointTrajectory topics, served by a second process
(``gateway_process.py``, one ``trajectory_gateway.py`` per controller) so that taking in a 100,000-point goal never
stalls the simulation; the pipe between the processes (``gateway_link.py``, the gateway's end ``sim_pipe.py``) and its
wire format (``cdr.py``, ``trajectory_cdr.py``). May import urscript, motion, robot, physics and description."""
