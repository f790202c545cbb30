"""URScript's syntax, in the subset ur_sim runs, parsed with lark (LALR): programs and statements to a tree.

A program is a ``def name():`` (or ``sec name():``) block, or bare statements; blocks end with ``end``. Line
breaks and indentation carry no meaning, as on the controller (ur_rtde's control script continues an assignment
on the line after a comment, and one-line programs such as ``def p(): movej(q) end`` are common); ``#`` starts a
comment, and ``$ 3 "MoveJ"``, the label lines of programs PolyScope writes, are skipped. Statements: assignments
(``global``/``local`` optional, to a variable or a list element), calls, ``if``/``elif``/``else``, ``while``,
``def`` functions with default arguments, ``return``, ``break``, ``continue``, ``halt``, ``pass``, and threads:
``thread name(): ... end``, ``run name()`` (an expression: the thread's handle), ``kill``, ``join``,
``enter_critical`` / ``exit_critical``. Expressions: numbers, ``True``/``False``,
strings, lists ``[..]``, poses ``p[..]``, indexing, calls with keyword arguments, ``+ - * / %``, comparisons,
``and or xor not``.
"""
from __future__ import annotations

import re
from functools import lru_cache

from lark import Lark, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from ur_sim_driver.errors import ScriptError

LITERALS = frozenset({'number', 'string', 'true', 'false'})  # the expressions that are their own value

GRAMMAR = r"""
program: statement*

?statement: funcdef | secdef | threaddef | if_stmt | while_stmt | simple_stmt
?simple_stmt: assign | call_stmt | return_stmt | break_stmt | continue_stmt | halt_stmt | pass_stmt
            | kill_stmt | join_stmt | enter_critical | exit_critical
assign: SCOPE? target "=" expr
?target: NAME -> var_target
       | NAME "[" expr ("," expr)? "]" -> index_target
call_stmt: call | run_thread
return_stmt: "return" expr?
break_stmt: "break"
continue_stmt: "continue"
halt_stmt: "halt"
pass_stmt: "pass"
kill_stmt: "kill" expr
join_stmt: "join" expr
enter_critical: "enter_critical"
exit_critical: "exit_critical"
funcdef: "def" NAME "(" params? ")" ":" block "end"
secdef: "sec" NAME "(" ")" ":" block "end"
threaddef: "thread" NAME "(" ")" ":" block "end"
params: param ("," param)*
param: NAME ("=" expr)?
block: statement*
if_stmt: "if" expr ":" block elif_clause* else_clause? "end"
elif_clause: "elif" expr ":" block
else_clause: "else" ":" block
while_stmt: "while" expr ":" block "end"

?expr: or_test
?or_test: xor_test | or_test "or" xor_test -> or_
?xor_test: and_test | xor_test "xor" and_test -> xor_
?and_test: not_test | and_test "and" not_test -> and_
?not_test: comparison | "not" not_test -> not_
?comparison: arith | arith COMP_OP arith -> compare
?arith: term | arith ADD_OP term -> binop
?term: factor | term MUL_OP factor -> binop
?factor: postfix | "-" factor -> neg | "+" factor
?postfix: atom | postfix "[" expr ("," expr)? "]" -> index | call | run_thread
call: NAME "(" args? ")"
run_thread: "run" NAME "(" ")"
args: arg ("," arg)*
?arg: expr | NAME "=" expr -> kwarg
?atom: NUMBER -> number
     | "True" -> true
     | "False" -> false
     | STRING -> string
     | "[" exprs? "]" -> list_
     | POSE_OPEN exprs? "]" -> pose
     | NAME -> var
     | "(" expr ")"
exprs: expr ("," expr)*

SCOPE.2: /(global|local)\b/
POSE_OPEN.2: /p\[/
COMP_OP: "==" | "!=" | "<=" | ">=" | "<" | ">"
ADD_OP: "+" | "-"
MUL_OP: "*" | "/" | "%"
NAME: /[A-Za-z_][A-Za-z0-9_]*/
NUMBER: /(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?/
STRING: /"[^"\n]*"/ | /'[^'\n]*'/
COMMENT: /#[^\n]*/
%ignore /[ \t\f\r\n]+/
%ignore /\\\r?\n/
%ignore COMMENT
"""


# PolyScope's program label lines (``$ 3 "MoveJ"``): blanked, so that lines keep their numbers
_LABEL = re.compile(r'^[ \t]*\$ *\d+\b[^\n]*$', re.MULTILINE)


@lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark(GRAMMAR, start='program', parser='lalr', propagate_positions=True, maybe_placeholders=False)


def parse(source: str) -> Tree:
    """The syntax tree of a URScript program or statements; ScriptError naming the line, the column and what was
    expected where the text is not URScript (the robot refuses such a program, and nothing runs)."""
    try:
        return _prepare(_parser().parse(_LABEL.sub('', source)))
    except UnexpectedToken as exc:
        line, column = exc.line, exc.column
        found = repr(str(exc.token))
        if exc.token.type == '$END':  # where the text ends (lark points at the last token)
            found = 'the end of the program'
            lines = source.rstrip('\r\n').split('\n')
            line, column = len(lines), len(lines[-1]) + 1
        expected = ', '.join(sorted(_describe(t) for t in exc.expected))
        raise ScriptError(f'syntax error on line {line}, column {column}: unexpected {found}; '
                          f'expected one of: {expected}', line, column) from None
    except UnexpectedCharacters as exc:
        raise ScriptError(f'syntax error on line {exc.line}, column {exc.column}: unexpected character '
                          f'{source.splitlines()[exc.line - 1][exc.column - 1]!r}', exc.line, exc.column) from None
    except UnexpectedInput as exc:  # the other lark errors: end of input
        raise ScriptError(f'syntax error on line {exc.line}, column {exc.column}: {exc}', exc.line,
                          exc.column) from None


def _prepare(tree: Tree) -> Tree:
    """Resolve once what every evaluation would otherwise work out again (the interpreter reads them): a literal's
    `literal` value, a variable's and a call's `name`, a call's `arguments` and whether all are plain (`plain`), a
    node's place `at` (line, column)."""
    for node in tree.iter_subtrees():
        kind = node.data
        if kind == 'number':
            text = str(node.children[0])
            node.literal = float(text) if any(c in text for c in '.eE') else int(text)
        elif kind == 'string':
            node.literal = str(node.children[0])[1:-1]
        elif kind in ('true', 'false'):
            node.literal = kind == 'true'
        elif kind == 'var':
            node.name = str(node.children[0])
        elif kind == 'call':
            node.name = str(node.children[0])
            node.arguments = [(str(a.children[0]), a.children[1]) if a.data == 'kwarg' else (None, a)
                              for a in (node.children[1].children if len(node.children) > 1 else [])]
            # every argument a variable or a literal: the call needs no generator (Interpreter._leaf)
            node.plain = all(expr.data == 'var' or expr.data in LITERALS for _, expr in node.arguments)
        if getattr(node.meta, 'line', None) is not None:
            node.at = (node.meta.line, node.meta.column)
    return tree


_TERMINALS = {'NAME': 'a name', 'NUMBER': 'a number', 'STRING': 'a string',
              'COMP_OP': 'a comparison', 'ADD_OP': '+ or -', 'MUL_OP': '*, / or %', 'SCOPE': 'global or local',
              'POSE_OPEN': 'p[', '$END': 'the end of the program'}


def _describe(terminal: str) -> str:
    if terminal in _TERMINALS:
        return _TERMINALS[terminal]
    pattern = _parser().get_terminal(terminal).pattern
    return repr(pattern.value) if pattern.type == 'str' else terminal
