"""The robot's own network ports, as a UR controller serves them: the dashboard server on TCP 29999
(``dashboard_port.py``). Plain sockets, no ROS: what answers is the simulated robot (the ``robot`` layer), the
same objects the ROS side talks to. May import controllers, gateway, motion, robot, physics and description."""
