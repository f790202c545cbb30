"""ur_sim_driver: a MuJoCo simulation of a Universal Robots arm behind the UR ROS 2 driver interfaces."""
