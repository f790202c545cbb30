"""URScript's syntax, in the subset ur_sim runs, parsed with lark (LALR): programs and statements to a tree.

A program is a ``def name():`` (or ``sec name():``) block, or bare statements; blocks end with ``end``;
indentation carries no meaning; ``#`` starts a comment. Statements: assignments (``global``/``local`` optional,
to a variable or a list element), calls, ``if``/``elif``/``else``, ``while``, ``def`` functions with default
arguments, ``return``, ``break``, ``continue``, ``halt``, ``pass``. Expressions: numbers, ``True``/``False``,
strings, lists ``[..]``, poses ``p[..]``, indexing, calls with keyword arguments, ``+ - * / %``, comparisons,
``and or xor not``.
"""
from __future__ import annotations

from functools import lru_cache

from lark import Lark, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from ur_sim_driver.errors import ScriptError

GRAMMAR = r"""
program: _NL* statement*

?statement: funcdef | secdef | if_stmt | while_stmt | simple_stmt
?simple_stmt: (assign | call_stmt | return_stmt | break_stmt | continue_stmt | halt_stmt | pass_stmt) _NL+
assign: SCOPE? target "=" expr
?target: NAME -> var_target
       | NAME "[" expr "]" -> index_target
call_stmt: call
return_stmt: "return" expr?
break_stmt: "break"
continue_stmt: "continue"
halt_stmt: "halt"
pass_stmt: "pass"
funcdef: "def" NAME "(" params? ")" ":" _NL+ block "end" _NL+
secdef: "sec" NAME "(" ")" ":" _NL+ block "end" _NL+
params: param ("," param)*
param: NAME ("=" expr)?
block: statement*
if_stmt: "if" expr ":" _NL+ block elif_clause* else_clause? "end" _NL+
elif_clause: "elif" expr ":" _NL+ block
else_clause: "else" ":" _NL+ block
while_stmt: "while" expr ":" _NL+ block "end" _NL+

?expr: or_test
?or_test: xor_test | or_test "or" xor_test -> or_
?xor_test: and_test | xor_test "xor" and_test -> xor_
?and_test: not_test | and_test "and" not_test -> and_
?not_test: comparison | "not" not_test -> not_
?comparison: arith | arith COMP_OP arith -> compare
?arith: term | arith ADD_OP term -> binop
?term: factor | term MUL_OP factor -> binop
?factor: postfix | "-" factor -> neg | "+" factor
?postfix: atom | postfix "[" expr "]" -> index | call
call: NAME "(" args? ")"
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
_NL: /\r?\n/
%ignore /[ \t\f]+/
%ignore /\\\r?\n/
%ignore COMMENT
"""


@lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark(GRAMMAR, start='program', parser='lalr', propagate_positions=True, maybe_placeholders=False)


def parse(source: str) -> Tree:
    """The syntax tree of a URScript program or statements; ScriptError naming the line, the column and what was
    expected where the text is not URScript (the robot refuses such a program, and nothing runs)."""
    try:
        return _parser().parse(source if source.endswith('\n') else source + '\n')
    except UnexpectedToken as exc:
        found = 'the end of a line' if exc.token.type == '_NL' else repr(str(exc.token))
        if exc.token.type == '$END':
            found = 'the end of the program'
        expected = ', '.join(sorted(_describe(t) for t in exc.expected))
        raise ScriptError(f'syntax error on line {exc.line}, column {exc.column}: unexpected {found}; '
                          f'expected one of: {expected}', exc.line, exc.column) from None
    except UnexpectedCharacters as exc:
        raise ScriptError(f'syntax error on line {exc.line}, column {exc.column}: unexpected character '
                          f'{source.splitlines()[exc.line - 1][exc.column - 1]!r}', exc.line, exc.column) from None
    except UnexpectedInput as exc:  # the other lark errors: end of input
        raise ScriptError(f'syntax error on line {exc.line}, column {exc.column}: {exc}', exc.line,
                          exc.column) from None


_TERMINALS = {'_NL': 'a new line', 'NAME': 'a name', 'NUMBER': 'a number', 'STRING': 'a string',
              'COMP_OP': 'a comparison', 'ADD_OP': '+ or -', 'MUL_OP': '*, / or %', 'SCOPE': 'global or local',
              'POSE_OPEN': 'p[', '$END': 'the end of the program'}


def _describe(terminal: str) -> str:
    if terminal in _TERMINALS:
        return _TERMINALS[terminal]
    pattern = _parser().get_terminal(terminal).pattern
    return repr(pattern.value) if pattern.type == 'str' else terminal
