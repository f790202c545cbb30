"""The URScript interpreter: walks the syntax tree of ``grammar.parse`` as generators, one per thread
(``threads.py`` schedules them), each yielding a request when its thread needs robot time (a motion, ``sleep``,
``sync``, ``join``), and running everything else at once.

What a statement does to the robot goes through :class:`ScriptRobot` (``program.py`` implements it on the simulated
robot, under the simulation lock). A name that is neither a variable nor a function, a wrong argument, an index
out of range: a :class:`~ur_sim_driver.errors.ScriptError` with the line and column, as the controller's runtime
exceptions have them; the program stops there.
"""
from __future__ import annotations

from collections.abc import Generator
from typing import Any, Protocol

from lark import Token, Tree

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.builtins import builtins
from ur_sim_driver.urscript.grammar import LITERALS
from ur_sim_driver.urscript.operators import arith, bind, compare, copy
from ur_sim_driver.urscript.threads import Threads
from ur_sim_driver.urscript.values import Pose, Request, ThreadHandle, is_number, show, truth

# A loop that runs this many times without spending robot time is the controller's "infinite loop" error.
MAX_ITERATIONS_WITHOUT_TIME = 100_000
_NOT_LEAF = object()  # _leaf's answer for an expression that needs evaluating


class ScriptRobot(Protocol):
    """What a program reads and sets on the robot (motions go out as Requests)."""

    def joint_positions(self) -> list[float]: ...
    def tcp_pose(self) -> Pose: ...
    def inverse_kin(self, pose: Pose, qnear: list[float] | None) -> list[float]: ...
    def set_digital_out(self, pin: int, on: bool) -> None: ...  # ur_msgs numbering: 0-7, 8-15, 16-17 (tool)
    def digital_out(self, pin: int) -> bool: ...
    def digital_in(self, pin: int) -> bool: ...
    def set_analog_out(self, pin: int, fraction: float) -> None: ...
    def set_payload(self, mass: float, cog: list[float]) -> None: ...
    def registers(self): ...  # robot.registers.Registers
    def textmsg(self, text: str) -> None: ...
    def sockets(self): ...  # ports.script_sockets.ScriptSockets: the program's client connections
    def interpreter_session(self): ...  # interpreter_session.InterpreterSession: the interpreter socket's queue


class _Return(Exception):
    def __init__(self, value) -> None:
        self.value = value


class _Break(Exception):
    pass


class _Continue(Exception):
    pass


class _Halt(Exception):
    pass


class Interpreter:
    """Runs one program's tree against `robot`: its main program is thread 0 of `threads`. `secondary`: a ``sec``
    program, which may not spend robot time (the controller refuses motion and sleep there)."""

    def __init__(self, tree: Tree, robot: ScriptRobot) -> None:
        self.robot = robot
        statements = list(tree.children)
        self.secondary = len(statements) == 1 and statements[0].data == 'secdef'
        if len(statements) == 1 and statements[0].data in ('funcdef', 'secdef'):
            self.name = str(statements[0].children[0])
            self.body = _block(statements[0])
        else:
            self.name = ''
            self.body = statements
        self.globals: dict[str, Any] = {}
        self.functions: dict[str, Tree] = {}
        self.thread_definitions: dict[str, Tree] = {}
        self.builtins = builtins(robot)
        self.threads = Threads()
        self.threads.start(self.name or 'main', lambda: self._body(self.body, self.globals))

    @property
    def line(self) -> int:
        """The line of the statement running (1-based) in the thread running now, or in the main program."""
        return (self.threads.current or self.threads.main).line

    @property
    def column(self) -> int:
        return (self.threads.current or self.threads.main).column

    def _body(self, statements, scope: dict) -> Generator[Request, None, None]:
        """A thread's statements (the main program's or a thread's): return ends the thread, halt the program."""
        try:
            yield from self._block(statements, scope)
        except _Halt:
            self.threads.halted = True
        except _Return:
            return
        except (_Break, _Continue) as exc:
            raise ScriptError(f'{type(exc).__name__[1:].lower()} outside a loop') from None

    # ---- statements --------------------------------------------------------------------------------------
    def _block(self, statements, scope: dict) -> Generator[Request, None, None]:
        for statement in statements:
            yield from self._statement(statement, scope)

    def _statement(self, node: Tree, scope: dict):
        kind = node.data
        thread = self.threads.current
        thread.line, thread.column = node.at  # where a request's failure points
        try:
            if kind == 'assign':
                yield from self._assign(node, scope)
            elif kind == 'call_stmt':
                result = self._leaf(node.children[0], scope)
                if result is _NOT_LEAF:
                    yield from self._eval(node.children[0], scope)
                elif type(result) is Request:
                    yield result
            elif kind == 'if_stmt':
                yield from self._if(node, scope)
            elif kind == 'while_stmt':
                yield from self._while(node, scope)
            elif kind in ('funcdef', 'secdef'):
                self.functions[str(node.children[0])] = node
            elif kind == 'threaddef':
                self.thread_definitions[str(node.children[0])] = node
            elif kind == 'kill_stmt':
                target = self.threads.find((yield from self._eval(node.children[0], scope)), 'kill')
                if target is not None:
                    self.threads.kill(target)
            elif kind == 'join_stmt':
                until = self.threads.join((yield from self._eval(node.children[0], scope)))
                if until is not None:
                    yield Request('join', (until,))
            elif kind == 'enter_critical':
                self.threads.enter_critical()
            elif kind == 'exit_critical':
                self.threads.exit_critical()
            elif kind == 'return_stmt':
                value = (yield from self._eval(node.children[0], scope)) if node.children else None
                raise _Return(value)
            elif kind == 'break_stmt':
                raise _Break()
            elif kind == 'continue_stmt':
                raise _Continue()
            elif kind == 'halt_stmt':
                raise _Halt()
        except ScriptError as exc:
            if exc.line == 0 and getattr(node.meta, 'line', None):
                raise ScriptError(f'line {node.meta.line}: {exc}', node.meta.line, node.meta.column) from None
            raise

    def _assign(self, node: Tree, scope: dict):
        children = list(node.children)
        declared = str(children.pop(0)) if isinstance(children[0], Token) and children[0].type == 'SCOPE' else None
        target, value_node = children
        value = self._leaf(value_node, scope)
        if value is _NOT_LEAF:
            value = yield from self._eval(value_node, scope)
        elif type(value) is Request:  # a built-in spending robot time
            value = yield value
        name = str(target.children[0])
        into = self.globals if declared == 'global' or (name in self.globals and name not in scope
                                                         and declared != 'local') else scope
        if target.data == 'var_target':
            into[name] = copy(value)
            return
        container = self._lookup(name, scope)
        subscripts = target.children[1:]  # m[i, j] = v: row i, column j of a matrix
        if isinstance(container, Pose) and len(subscripts) == 1:  # a pose's element: the variable gets a new pose
            index = self._index((yield from self._eval(subscripts[0], scope)), 6, name)
            if not is_number(value):
                raise ScriptError(f'{name}[{index}] is a number (a pose holds 6); got {show(value)}')
            values = list(container.values)
            values[index] = float(value)
            (scope if name in scope else self.globals)[name] = Pose(tuple(values))
            return
        for k, subscript in enumerate(subscripts):
            index = yield from self._eval(subscript, scope)
            if not isinstance(container, list):
                raise ScriptError(f'{name} is not a list; only list elements can be assigned by index')
            index = self._index(index, len(container), name)
            if k == len(subscripts) - 1:
                container[index] = copy(value)
            else:
                container = container[index]

    def _if(self, node: Tree, scope: dict):
        children = node.children
        if truth((yield from self._eval(children[0], scope))):
            yield from self._block(children[1].children, scope)
            return
        for clause in children[2:]:
            if clause.data == 'elif_clause':
                if truth((yield from self._eval(clause.children[0], scope))):
                    yield from self._block(clause.children[1].children, scope)
                    return
            else:
                yield from self._block(clause.children[0].children, scope)
                return

    def _while(self, node: Tree, scope: dict):
        condition, body = node.children
        thread = self.threads.current
        while truth((yield from self._eval(condition, scope))):
            thread.spinning += 1
            if thread.spinning > MAX_ITERATIONS_WITHOUT_TIME:
                raise ScriptError(f'infinite loop detected: the loop on line {node.meta.line} ran '
                                  f'{MAX_ITERATIONS_WITHOUT_TIME} times without spending robot time (add sync() or '
                                  'sleep())', node.meta.line, node.meta.column)
            try:
                yield from self._block(body.children, scope)
            except _Break:
                break
            except _Continue:
                continue

    # ---- expressions -------------------------------------------------------------------------------------
    def _eval(self, node, scope: dict):
        kind = node.data
        if kind == 'var':
            return self._lookup(node.name, scope)
        if kind in LITERALS:
            return node.literal
        if kind == 'call':
            return (yield from self._call(node, scope))
        if kind in ('list_', 'pose'):
            items = [c for c in node.children if isinstance(c, Tree)]
            values = []
            for expr in (items[0].children if items else []):
                value = self._leaf(expr, scope)
                if value is _NOT_LEAF:
                    value = yield from self._eval(expr, scope)
                elif type(value) is Request:
                    value = yield value
                values.append(value)
            if kind == 'list_':
                return values
            if len(values) == 1 and self._defined('p', scope):  # p[i] of a variable named p, not a pose literal
                return self._element(self._lookup('p', scope), values[0])
            if len(values) != 6 or not all(is_number(v) for v in values):
                raise ScriptError(f'a pose has 6 numbers (x, y, z [m], rx, ry, rz [rad]); got {show(values)}')
            return Pose(tuple(float(v) for v in values))
        if kind == 'index':
            value = self._leaf(node.children[0], scope)
            if value is _NOT_LEAF:
                value = yield from self._eval(node.children[0], scope)
            elif type(value) is Request:  # a built-in spending robot time
                value = yield value
            for subscript in node.children[1:]:  # m[i, j]: row i, column j of a matrix (a list of rows)
                index = self._leaf(subscript, scope)
                if index is _NOT_LEAF:
                    index = yield from self._eval(subscript, scope)
                elif type(index) is Request:  # a built-in spending robot time
                    index = yield index
                value = self._element(value, index)
            return value
        if kind == 'run_thread':
            return self._run_thread(str(node.children[0]))
        if kind == 'neg':
            value = yield from self._eval(node.children[0], scope)
            return arith('-', 0, value) if not isinstance(value, list) else [-v for v in value]
        if kind == 'not_':
            return not truth((yield from self._eval(node.children[0], scope)))
        if kind in ('and_', 'or_', 'xor_'):
            left = truth((yield from self._eval(node.children[0], scope)))
            if kind == 'and_' and not left:
                return False
            if kind == 'or_' and left:
                return True
            right = truth((yield from self._eval(node.children[1], scope)))
            return left != right if kind == 'xor_' else right
        if kind == 'compare' or kind == 'binop':
            left_node, op, right_node = node.children
            left = self._leaf(left_node, scope)
            if left is _NOT_LEAF:
                left = yield from self._eval(left_node, scope)
            elif type(left) is Request:  # a built-in spending robot time
                left = yield left
            right = self._leaf(right_node, scope)
            if right is _NOT_LEAF:
                right = yield from self._eval(right_node, scope)
            elif type(right) is Request:  # a built-in spending robot time
                right = yield right
            return (compare if kind == 'compare' else arith)(str(op), left, right)
        if kind == 'factor':  # unary plus
            return (yield from self._eval(node.children[0], scope))
        raise ScriptError(f'{kind} is not supported by ur_sim')

    def _element(self, value, index):
        items = value.values if isinstance(value, Pose) else value
        if not isinstance(items, (list, tuple)):
            raise ScriptError(f'{show(value)} cannot be indexed (not a list, matrix or pose)')
        return items[self._index(index, len(items), 'the list')]

    def _defined(self, name: str, scope: dict) -> bool:
        return name in scope or name in self.globals

    def _leaf(self, node: Tree, scope: dict):
        """Without a generator (most operands need none): a variable's or a literal's value, or a built-in's result
        whose arguments are such (a Request: the caller yields it); else _NOT_LEAF. Its callers repeat the four
        lines that use it: a helper generator would cost the generator this avoids."""
        kind = node.data
        if kind == 'var':
            return self._lookup(node.name, scope)
        if kind in LITERALS:
            return node.literal
        if kind == 'call' and node.plain and node.name not in self.functions and node.name in self.builtins:
            positional, keywords = [], {}
            for keyword, expr in node.arguments:
                value = self._lookup(expr.name, scope) if expr.data == 'var' else expr.literal
                if keyword is None:
                    positional.append(value)
                else:
                    keywords[keyword] = value
            return self._builtin(node.name, positional, keywords)
        return _NOT_LEAF

    def _lookup(self, name: str, scope: dict):
        if name in scope:
            return scope[name]
        if name in self.globals:
            return self.globals[name]
        raise ScriptError(f'variable {name!r} is not defined')

    @staticmethod
    def _index(index, length: int, what: str) -> int:
        if not isinstance(index, int) or isinstance(index, bool):
            raise ScriptError(f'an index is an integer; got {show(index)}')
        if not 0 <= index < length:
            raise ScriptError(f'index {index} is out of range for {what} of length {length}')
        return index

    def _call(self, node: Tree, scope: dict):
        name = str(node.children[0])
        positional, keywords = [], {}
        if len(node.children) > 1:
            for arg in node.children[1].children:
                keyword = arg.data == 'kwarg'
                expr = arg.children[1] if keyword else arg
                value = self._leaf(expr, scope)
                if value is _NOT_LEAF:
                    value = yield from self._eval(expr, scope)
                elif type(value) is Request:  # a built-in spending robot time
                    value = yield value
                if keyword:
                    keywords[str(arg.children[0])] = value
                else:
                    positional.append(value)
        if name in self.functions:
            return (yield from self._user_call(self.functions[name], positional, keywords))
        if name == 'interpreter_mode':
            return (yield from self._interpreter_mode(positional, keywords, scope))
        result = self._builtin(name, positional, keywords)
        if type(result) is Request:
            return (yield result)
        return result

    def _builtin(self, name: str, positional: list, keywords: dict):
        """A built-in function's result, or the Request for the robot time it spends."""
        if name not in self.builtins:
            raise ScriptError(f'unknown function {name!r}: it is not defined in the program and not among the '
                              'functions ur_sim supports (docs/urscript.md)')
        parameters, function = self.builtins[name]
        result = function(*bind(name, parameters, positional, keywords))
        if type(result) is Request and self.secondary:
            raise ScriptError(f'{name}: a secondary program (sec) cannot spend robot time; use a def program')
        return result

    def _interpreter_mode(self, positional: list, keywords: dict, scope: dict):
        """interpreter_mode(clearQueueOnEnter=True, clearOnEnd=True): execute the statements the interpreter socket
        takes, in order and in this scope, until end_interpreter(); sync while none waits."""
        clear_queue, clear_on_end = bind('interpreter_mode', [('clearQueueOnEnter', True), ('clearOnEnd', True)],
                                          positional, keywords)
        thread = self.threads.current
        if self.secondary or thread.number != 0:
            raise ScriptError('interpreter_mode() can only be called in the main thread of a def program')
        session = self.robot.interpreter_session()
        session.enter(truth(clear_queue))
        try:
            while not session.ended:
                item = session.next()
                if item is None:
                    yield Request('sync')
                else:
                    yield from self._block(item[1], scope)
        finally:
            session.leave(truth(clear_on_end))
        return None

    def _run_thread(self, name: str) -> ThreadHandle:
        definition = self.thread_definitions.get(name)
        if definition is None:
            known = ', '.join(sorted(self.thread_definitions)) or 'none'
            raise ScriptError(f'run: no thread named {name!r} is defined (threads defined so far: {known})')
        if self.secondary:
            raise ScriptError('run: a secondary program (sec) cannot start threads')
        return self.threads.start(name, lambda: self._body(_block(definition), {})).handle

    def _user_call(self, definition: Tree, positional: list, keywords: dict):
        name = str(definition.children[0])
        signature = getattr(definition, 'signature', None)
        if signature is None:  # the arguments and their defaults, worked out at the first call
            params = [c for c in definition.children[1:] if isinstance(c, Tree) and c.data == 'params']
            spec = [(str(p.children[0]), p.children[1] if len(p.children) > 1 else None)
                    for p in (params[0].children if params else [])]
            signature = definition.signature = (spec, [n for n, _ in spec], _block(definition))
        spec, names, body = signature
        if len(positional) > len(spec):
            raise ScriptError(f'{name}() takes at most {len(spec)} arguments; got {len(positional)}')
        local: dict[str, Any] = dict(zip(names, positional))
        for key, value in keywords.items():
            if key not in names:
                raise ScriptError(f'{name}() has no argument {key!r}; its arguments: {", ".join(names)}')
            local[key] = value
        for param, default in spec:
            if param not in local:
                if default is None:
                    raise ScriptError(f'{name}() needs argument {param!r} ({", ".join(names)})')
                local[param] = yield from self._eval(default, self.globals)
        try:
            yield from self._block(body, local)
        except _Return as ret:
            return ret.value
        return None


def _block(definition: Tree) -> list:
    return next(c for c in definition.children if isinstance(c, Tree) and c.data == 'block').children
