"""Every port's connections are configured so that a peer that is gone ends them (a half-open connection): TCP
keepalive and a user timeout on the accepted socket, before the port's own code sees it."""
import socket
import threading

import pytest

from ur_sim_driver.ports.tcp_port import KEEPALIVE, USER_TIMEOUT, PortError, TcpPort

pytestmark = pytest.mark.timeout(30)


def test_an_accepted_connection_has_keepalive_and_a_user_timeout():
    seen: dict[str, int] = {}
    served = threading.Event()

    def serve(sock: socket.socket) -> None:
        seen['keepalive'] = sock.getsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE)
        seen['idle'] = sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPIDLE)
        seen['count'] = sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPCNT)
        seen['user_timeout'] = sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_USER_TIMEOUT)
        seen['nodelay'] = sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY)
        served.set()

    port = TcpPort('test port', '127.0.0.1', 0, serve)
    try:
        with socket.create_connection(port.address, timeout=10.0):
            assert served.wait(10.0)
        assert seen == {'keepalive': 1, 'idle': KEEPALIVE[0], 'count': KEEPALIVE[2], 'user_timeout': USER_TIMEOUT,
                        'nodelay': 1}
    finally:
        port.close()


def test_an_address_in_use_names_the_port_and_the_address():
    port = TcpPort('first', '127.0.0.1', 0, lambda sock: None)
    try:
        with pytest.raises(PortError, match=rf'second: cannot listen on 127.0.0.1:{port.address[1]}: '):
            TcpPort('second', '127.0.0.1', port.address[1], lambda sock: None)
    finally:
        port.close()
