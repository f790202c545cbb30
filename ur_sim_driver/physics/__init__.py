"""MuJoCo: stepping the arm model, contacts and force-torque sensors from the finished step (``physics.py``),
the joint servo and computed-torque control (compiled per cycle with numba). No ROS. May import description."""
