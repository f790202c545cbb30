"""The UR driver's ros2_control controllers, one module each (``base.py``: their lifecycle and the host they run
in), the controller manager (pure ``controller_manager.py`` and ``controller_lifecycle.py``; its node
``controller_manager_node.py`` with ``lifecycle_services.py`` and ``hardware_services.py``), the hardware component
(pure ``hardware_component.py``, its interfaces and modes in ``ur_hardware.py``), what the driver's launch file
starts (``startup.py``), the robot_state_helper's decisions (``set_mode.py``) and the message packing the
controllers share (``cdr_template.py``, ``controller_state.py``). May import gateway, urscript, motion, robot,
physics and description."""
