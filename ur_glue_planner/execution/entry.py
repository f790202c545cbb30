"""What the planner's executables (`ur_glue_planner`, `ur_glue_studio`) do first: start rclpy with their own
signal handling and read their `--ros-args` parameters."""
from __future__ import annotations

import signal
import threading
from typing import Any

import rclpy
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions


def start_ros(node_name: str, argv: list[str] | None) -> tuple[dict[str, Any], threading.Event]:
    """Initialise rclpy's default context and read the parameters given for `node_name`.

    Returns:
        (parameters by name, an event set on SIGINT or SIGTERM): the executable stops its work cleanly
        (cancelling a goal, closing a server) instead of being interrupted wherever it is.
    """
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    node = Node(node_name, allow_undeclared_parameters=True, automatically_declare_parameters_from_overrides=True)
    params = {name: p.value for name, p in node.get_parameters_by_prefix('').items()}
    node.destroy_node()
    return params, stop
