"""Robot descriptions (URDF for kinematics, MJCF for MuJoCo) generated from one parameter set per UR type."""
