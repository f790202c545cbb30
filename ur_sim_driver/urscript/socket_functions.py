"""URScript's socket functions, with the controller's arguments, defaults and return values: a program's client
connections by name (default ``socket_0``), several at once. Reads wait in robot time for what they need and only
their own thread waits; on a timeout or a socket that is not open they return what the manual gives (``[0, -1,
...]`` for the list reads, ``""`` for strings), and a timeout <= 0 waits for ever. Binary integers are 32-bit, big
endian (network order). The connections themselves belong to the program's sockets object (``ScriptSockets`` in
``ports/script_sockets.py``), reached through ``robot.sockets()``.
"""
from __future__ import annotations

import math
import re
import struct
from collections.abc import Callable

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.values import REQUIRED, Request, is_number, show

MAX_READ = 30  # numbers one read may ask for
DEFAULT = 'socket_0'
_FLOAT = re.compile(rb'\(([^()]*)\)')


def _count(name: str, number) -> int:
    if not isinstance(number, int) or isinstance(number, bool) or not 1 <= number <= MAX_READ:
        raise ScriptError(f'{name}: number is an integer in [1, {MAX_READ}]; got {show(number)}')
    return number


def _name(function: str, socket_name) -> str:
    if not isinstance(socket_name, str):
        raise ScriptError(f'{function}: socket_name is a string; got {show(socket_name)}')
    return socket_name


def _timeout(function: str, timeout) -> float:
    if not is_number(timeout) or not math.isfinite(timeout):
        raise ScriptError(f'{function}: timeout is a number of seconds (<= 0: no timeout); got {show(timeout)}')
    return float(timeout)


def _integers(n: int) -> Callable[[bytearray], tuple[int, list] | None]:
    size = 4 * n

    def parse(data: bytearray):
        if len(data) < size:
            return None
        return size, [n, *struct.unpack(f'>{n}i', bytes(data[:size]))]
    return parse


def _bytes(n: int):
    def parse(data: bytearray):
        return (n, [n, *data[:n]]) if len(data) >= n else None
    return parse


def _ascii_floats(n: int):
    """``(1.5, 2, -3e-2)``: what precedes the parenthesis is skipped; a count other than `n` is an invalid reply."""
    def parse(data: bytearray):
        match = _FLOAT.search(data)
        if match is None:
            return None
        try:
            values = [float(v) for v in match.group(1).split(b',')]
        except ValueError:
            values = []
        return match.end(), ([len(values), *values] if len(values) == n else [0] + [-1.0] * n)
    return parse


def _line(data: bytearray):
    end = data.find(b'\n')
    return None if end < 0 else (end + 1, data[:end].rstrip(b'\r').decode('latin-1'))


def _between(prefix: str, suffix: str, escapes: bool):
    """What comes after `prefix` (when given) and before `suffix` (when given; else all that has come); `escapes`:
    the two-character escapes \\n, \\t, ... turned into their characters."""
    head, tail = prefix.encode('latin-1'), suffix.encode('latin-1')

    def text(raw: bytearray) -> str:
        return raw.decode('unicode_escape') if escapes else raw.decode('latin-1')

    def parse(data: bytearray):
        start = 0
        if head:
            found = data.find(head)
            if found < 0:
                return None
            start = found + len(head)
        if tail:
            end = data.find(tail, start)
            return None if end < 0 else (end + len(tail), text(data[start:end]))
        return None if len(data) <= start else (len(data), text(data[start:]))
    return parse


def socket_functions(robot) -> dict[str, tuple[list, Callable]]:
    """name -> ([(argument, default or REQUIRED)], function), as ``builtins.builtins``."""
    R = REQUIRED

    def sockets():
        return robot.sockets()

    def wait(poll) -> Request:
        return Request('wait', (poll,))

    def socket_open(address, port, socket_name=DEFAULT):
        if not isinstance(address, str):
            raise ScriptError(f'socket_open: address is a string; got {show(address)}')
        if not isinstance(port, int) or isinstance(port, bool) or not 1 <= port <= 65535:
            raise ScriptError(f'socket_open: port is an integer in [1, 65535]; got {show(port)}')
        return wait(sockets().open(address, port, _name('socket_open', socket_name)))

    def send(function: str, socket_name, data: bytes) -> bool:
        return sockets().send(_name(function, socket_name), data)

    def send_string(value, socket_name=DEFAULT):
        return send('socket_send_string', socket_name, show(value).encode('latin-1'))

    def send_line(value, socket_name=DEFAULT):
        return send('socket_send_line', socket_name, show(value).encode('latin-1') + b'\n')

    def send_byte(value, socket_name=DEFAULT):
        if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 255:
            raise ScriptError(f'socket_send_byte: value is an integer in [0, 255]; got {show(value)}')
        return send('socket_send_byte', socket_name, bytes([value]))

    def send_int(value, socket_name=DEFAULT):
        if not is_number(value) or not -2**31 <= value < 2**31:
            raise ScriptError(f'socket_send_int: value is a 32-bit integer; got {show(value)}')
        return send('socket_send_int', socket_name, struct.pack('>i', int(value)))

    def read(function, socket_name, parse, timeout, failure):
        return wait(sockets().read(_name(function, socket_name), parse, _timeout(function, timeout), failure))

    def read_integers(number, socket_name=DEFAULT, timeout=2.0):
        n = _count('socket_read_binary_integer', number)
        return read('socket_read_binary_integer', socket_name, _integers(n), timeout, [0] + [-1] * n)

    def read_floats(number, socket_name=DEFAULT, timeout=2.0):
        n = _count('socket_read_ascii_float', number)
        return read('socket_read_ascii_float', socket_name, _ascii_floats(n), timeout, [0] + [-1.0] * n)

    def read_bytes(number, socket_name=DEFAULT, timeout=2.0):
        n = _count('socket_read_byte_list', number)
        return read('socket_read_byte_list', socket_name, _bytes(n), timeout, [0] + [-1] * n)

    def read_string(socket_name=DEFAULT, prefix='', suffix='', interpret_escape=False, timeout=2.0):
        if not isinstance(prefix, str) or not isinstance(suffix, str):
            raise ScriptError(f'socket_read_string: prefix and suffix are strings; got {show(prefix)}, '
                              f'{show(suffix)}')
        return read('socket_read_string', socket_name, _between(prefix, suffix, bool(interpret_escape)), timeout, '')

    def read_line(socket_name=DEFAULT, timeout=2.0):
        return read('socket_read_line', socket_name, _line, timeout, '')

    def get_var(name, socket_name=DEFAULT):
        if not isinstance(name, str):
            raise ScriptError(f'socket_get_var: name is a string; got {show(name)}')
        socket_name = _name('socket_get_var', socket_name)
        if not sockets().send(socket_name, f'GET {name}\n'.encode('latin-1')):
            return 0

        def parse(data):  # the server answers "NAME value\n"
            got = _line(data)
            if got is None:
                return None
            words = got[1].split()
            try:
                return got[0], int(float(words[1])) if len(words) == 2 and words[0] == name else 0
            except ValueError:
                return got[0], 0
        return read('socket_get_var', socket_name, parse, 2.0, 0)

    def set_var(name, value, socket_name=DEFAULT):
        if not isinstance(name, str) or not is_number(value):
            raise ScriptError(f'socket_set_var: name is a string and value an integer; got {show(name)}, '
                              f'{show(value)}')
        send('socket_set_var', socket_name, f'SET {name} {int(value)}\n'.encode('latin-1'))

    return {
        'socket_open': ([('address', R), ('port', R), ('socket_name', DEFAULT)], socket_open),
        'socket_close': ([('socket_name', DEFAULT)], lambda n=DEFAULT: sockets().close(_name('socket_close', n))),
        'socket_send_string': ([('str', R), ('socket_name', DEFAULT)], send_string),
        'socket_send_line': ([('str', R), ('socket_name', DEFAULT)], send_line),
        'socket_send_byte': ([('value', R), ('socket_name', DEFAULT)], send_byte),
        'socket_send_int': ([('value', R), ('socket_name', DEFAULT)], send_int),
        'socket_read_binary_integer': ([('number', R), ('socket_name', DEFAULT), ('timeout', 2.0)], read_integers),
        'socket_read_ascii_float': ([('number', R), ('socket_name', DEFAULT), ('timeout', 2.0)], read_floats),
        'socket_read_byte_list': ([('number', R), ('socket_name', DEFAULT), ('timeout', 2.0)], read_bytes),
        'socket_read_string': ([('socket_name', DEFAULT), ('prefix', ''), ('suffix', ''),
                                ('interpret_escape', False), ('timeout', 2.0)], read_string),
        'socket_read_line': ([('socket_name', DEFAULT), ('timeout', 2.0)], read_line),
        'socket_get_var': ([('name', R), ('socket_name', DEFAULT)], get_var),
        'socket_set_var': ([('name', R), ('value', R), ('socket_name', DEFAULT)], set_var),
    }
