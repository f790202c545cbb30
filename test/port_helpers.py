"""What the port tests' own clients share."""
import socket


def recv_exactly(sock: socket.socket, n: int) -> bytes:
    """`n` bytes from `sock` (its timeout applies to each read); fails if the server closes the connection first."""
    data = b''
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        assert chunk, 'the server closed the connection'
        data += chunk
    return data
