"""A blocking call of an idempotent ROS service that sends its request again while no answer comes.

ROS 2 drops a service's answer that is sent before DDS has matched the client's response reader with the server;
``wait_for_service`` only proves the other direction. On a loaded machine the matching can lag by seconds, and
the first answers are then lost for good. Calls that may safely be repeated (switching an output off, clearing
the bead) are therefore sent again every ``resend`` seconds until one answer arrives.
"""
from __future__ import annotations

import time

from rclpy.client import Client

from ur_glue_planner.errors import ClientError

POLL = 0.005  # [s] between looks at the pending answers


def call_idempotent(client: Client, request: object, what: str, timeout: float = 5.0, resend: float = 1.0):
    """Send `request` on `client` (its executor spins elsewhere) and return the first answer.

    Args:
        what: the call in words, for the error (e.g. 'switching pin 16 off').
        timeout: [s] of wall time for an answer to any of the requests.
        resend: [s] of wall time after which an unanswered request is sent again.

    Raises:
        ClientError: no answer within `timeout`, naming the service, `what` and the number of requests sent.
    """
    deadline = time.monotonic() + timeout
    futures = []
    while True:
        futures.append(client.call_async(request))
        again = time.monotonic() + resend
        while time.monotonic() < again:
            answered = next((f for f in futures if f.done()), None)
            if answered is not None:
                return answered.result()
            if time.monotonic() > deadline:
                raise ClientError(f'{client.srv_name}: no answer to {what} within {timeout:.1f} s '
                                  f'({len(futures)} requests sent)')
            time.sleep(POLL)
