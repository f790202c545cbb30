"""The robot's own network ports, as a UR controller serves them, each on a ``tcp_port.TcpPort`` (line protocols on
``tcp_port.LinePort``): the dashboard server on TCP 29999 (``dashboard_port.py``), RTDE on 30004 (``rtde_port.py``,
with the protocol in ``rtde_protocol.py`` and what each variable reads and writes in ``rtde_fields.py``), the primary,
secondary and real-time interfaces on 30001-30003 (``primary_port.py``, the packages in ``primary_messages.py`` and
``realtime_messages.py``), the interpreter socket on 30020 (``interpreter_port.py``), and the client connections a
URScript program opens (``script_sockets.py``). Plain sockets, no ROS: what answers is the simulated robot, the same
objects the ROS side talks to. May import controllers, gateway, urscript, motion, robot, physics and description."""
