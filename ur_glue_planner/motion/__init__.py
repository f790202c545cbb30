"""Motion: kinematics, IK branch choice, the bead in joint space, the moves onto and off it, and plan_job."""
