"""The gateway process's end of the pipe to the simulation, shared by its controllers.

One sender at a time; the questions a controller asks the simulation (may it take this goal or message now?,
``gateway_link.Admit``) wait here for their ``Admission``, which the process's receiving thread hands in.
"""
from __future__ import annotations

import itertools
import threading
from multiprocessing.connection import Connection

from ur_sim_driver.gateway.gateway_link import Admission, Admit

# How long a goal or message waits for the simulation's Admission [s of wall time]: the simulation answers from
# its receiving thread at once, so only a simulation that is gone or hung takes this long.
ADMIT_TIMEOUT = 10.0


class SimPipe:
    """What the controllers of this process share: the pipe (one sender at a time) and the questions to the
    simulation that wait for its answer."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self._send_lock = threading.Lock()
        self._numbers = itertools.count()
        self._lock = threading.Lock()
        self._asked: dict[int, list] = {}  # request -> [event, Admission | None]

    def admit(self, controller: str, topic: bool) -> Admission | None:
        """Ask the simulation whether `controller` may take a goal (or a topic message) now; None if it does not
        answer within ADMIT_TIMEOUT."""
        request = next(self._numbers)
        slot = [threading.Event(), None]
        with self._lock:
            self._asked[request] = slot
        self.send(Admit(request, controller, topic))
        slot[0].wait(ADMIT_TIMEOUT)
        with self._lock:
            self._asked.pop(request, None)
        return slot[1]

    def answered(self, admission: Admission) -> None:
        with self._lock:
            slot = self._asked.get(admission.request)
        if slot is not None:
            slot[1] = admission
            slot[0].set()

    def end_all(self) -> None:
        """The simulation is gone: every question ends unanswered."""
        with self._lock:
            slots = list(self._asked.values())
        for slot in slots:
            slot[0].set()

    def send(self, message: object) -> None:
        """Send `message` to the simulation (one sender at a time); nothing when it is gone."""
        with self._send_lock:
            try:
                self.conn.send(message)
            except (OSError, BrokenPipeError):
                pass  # the simulation is gone; the receiving thread ends every goal
