"""ur_sim_driver: a MuJoCo simulation of a Universal Robots arm behind the UR ROS 2 driver interfaces.

Layers, each a subpackage; a module imports only from its own layer, the layers below it, the module at the top
(``errors``, the package's exception family), which imports nothing of ours, and ``ur_common`` (the ground shared
with ur_glue_planner: the action client, the executor thread, file locations); ``test/test_layers.py`` checks it:

    ros          the ur_sim node, the dashboard services, robot_state_publisher, IO and wrench components
    ports        the robot's own network ports: the dashboard server on TCP 29999, RTDE on 30004
    controllers  the driver's ros2_control controllers, one module each, and the controller manager
    gateway      the trajectory controllers' action and topic interfaces, in a process of their own
    urscript     the URScript subset: parser, interpreter, the moves a script commands, the program slot
    motion       trajectories, their sampling, tolerances and validation, the trajectory controller core
    robot        the simulated robot: its state, safety, dashboard, IO, payload, speed scaling, glue gun
    physics      MuJoCo stepping, contacts and sensors, the joint servo and torque control
    description  URDF and MJCF from UR parameters, the tool, the scene and the glue bead's shape and message

ur_glue_planner stands on the shared ground only: ``ur_common`` and ``description``, never the simulator's runtime
(the planner must drive a real robot just as well).
"""
