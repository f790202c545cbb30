"""Robot descriptions (URDF for kinematics, MJCF for MuJoCo) generated from one parameter set per UR type, the
tool, the scene (windshield, table), and the glue bead (``bead.py``: its section, its PointCloud2 layout, its
drawing), the closed-form IK of the arms (``analytic_ik.py``). The ground shared with ur_glue_planner. No rclpy
(``bead.py`` builds sensor_msgs messages). Imports nothing of ur_sim_driver but ``errors`` and ``paths``."""
