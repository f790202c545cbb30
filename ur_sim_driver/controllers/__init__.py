"""The UR driver's ros2_control controllers, one module each (``base.py``: their lifecycle and the host they run
in), the controller manager (pure ``controller_manager.py``, services in ``controller_manager_node.py``), the
hardware component's interfaces (``ur_hardware.py``) and the message packing they share (``cdr_template.py``,
``controller_state.py``). May import gateway, motion, robot, physics and description."""
