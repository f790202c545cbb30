"""URScript's operators and argument binding, pure: arithmetic on numbers, lists (element-wise) and poses,
comparisons, the copy an assignment makes of a list, and how a call's arguments meet a function's parameters."""
from __future__ import annotations

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.values import REQUIRED, Pose, is_number, show


def bind(name: str, parameters: list, positional: list, keywords: dict) -> list:
    """Arguments in parameter order; parameters are (name, default or REQUIRED)."""
    names = [p for p, _ in parameters]
    if len(positional) > len(parameters):
        raise ScriptError(f'{name}() takes at most {len(parameters)} arguments ({", ".join(names)}); '
                          f'got {len(positional)}')
    values = list(positional) + [None] * (len(parameters) - len(positional))
    for key, value in keywords.items():
        if key not in names:
            raise ScriptError(f'{name}() has no argument {key!r}; its arguments: {", ".join(names)}')
        values[names.index(key)] = value
    for k, (param, default) in enumerate(parameters):
        if values[k] is None and k >= len(positional) and param not in keywords:
            if default is REQUIRED:
                raise ScriptError(f'{name}() needs argument {param!r} ({", ".join(names)})')
            values[k] = default
    return values


def copy(value):
    return [copy(v) for v in value] if isinstance(value, list) else value


def compare(op: str, a, b) -> bool:
    if op in ('==', '!='):
        equal = (a == b) if not (isinstance(a, Pose) or isinstance(b, Pose)) else a == b
        return equal if op == '==' else not equal
    if not (is_number(a) and is_number(b)):
        raise ScriptError(f'{show(a)} {op} {show(b)}: only numbers are ordered')
    return {'<': a < b, '>': a > b, '<=': a <= b, '>=': a >= b}[op]


def arith(op: str, a, b):
    if isinstance(a, str) and isinstance(b, str) and op == '+':
        return a + b
    if isinstance(a, Pose) and isinstance(b, Pose) and op in '+-':
        sign = 1.0 if op == '+' else -1.0
        return Pose(tuple(x + sign * y for x, y in zip(a.values, b.values)))
    if isinstance(a, list) or isinstance(b, list):
        la = a if isinstance(a, list) else [a] * len(b)
        lb = b if isinstance(b, list) else [b] * len(a)
        if len(la) != len(lb):
            raise ScriptError(f'{show(a)} {op} {show(b)}: the lists differ in length')
        return [arith(op, x, y) for x, y in zip(la, lb)]
    if not (is_number(a) and is_number(b)):
        raise ScriptError(f'{show(a)} {op} {show(b)}: not numbers')
    if op == '+':
        return a + b
    if op == '-':
        return a - b
    if op == '*':
        return a * b
    if b == 0:
        raise ScriptError(f'{show(a)} {op} 0: division by zero')
    if op == '/':
        return a // b if isinstance(a, int) and isinstance(b, int) and a % b == 0 else a / b
    return a % b


