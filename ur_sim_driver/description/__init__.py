"""Robot descriptions (URDF for kinematics, MJCF for MuJoCo) generated from one parameter set per UR type, the
tool, and the scene (windshield, table). No ROS. Imports nothing of ur_sim_driver but ``errors`` and ``paths``."""
