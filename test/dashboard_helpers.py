"""The driver's dashboard_client services as a test calls them: one client per service, each waited for."""
from __future__ import annotations

from sim_harness import wait_answer, wait_still


class DashboardServices:
    """Clients on `h`'s node for `types` ({service name: type}) under /dashboard_client, left for the harness's
    teardown: destroyed under its spinning executor, rclpy can kill that thread (InvalidHandle)."""

    def __init__(self, h, types: dict[str, type]) -> None:
        self.h, self.types = h, types
        self.clients = {n: h.client.create_client(t, f'/dashboard_client/{n}') for n, t in types.items()}
        for name, client in self.clients.items():
            wait_still(client.service_is_ready, what=f'/dashboard_client/{name}')

    def call(self, name: str, **fields):
        """The answer of service `name` to a request with `fields`."""
        request = self.types[name].Request(**fields)
        return wait_answer(self.clients[name].call_async(request), f'the answer of /dashboard_client/{name}')
