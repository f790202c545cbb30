"""The emulated ros2_control controllers of the UR driver, one module each (see ``base.py`` for the lifecycle)."""
