"""The ROS edge: the ``ur_sim`` node (``node.py``) composing the simulation, the controllers and the components
the driver's other nodes provide (dashboard client services, robot_state_publisher, the IO and force-torque
hardware); the loop's thread that steps it (``sim_loop.py``), the executable around it (``main.py``) and the wait
for a client in step with it (``pace_gate.py``).
May import every layer below (ports, controllers, gateway, urscript, motion, robot, physics, description)."""
