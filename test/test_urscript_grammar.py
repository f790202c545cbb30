"""URScript's syntax as ur_sim parses it: what compiles, and what is refused with the line, the column and the
reason (as the controller refuses a program that does not compile)."""
import pytest

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.grammar import parse

PROGRAM = '''def prog():
  # a comment
  global x = 1 + 2 * 3   # precedence: 7
  q = [0, -1.57, 1.57, -1.57, -1.57, 0.]
  target = p[0.1, .2, 0.3, 0, 3.14, 1e-3]
  if x > 3 and not False:
    movej(q, a=1.2, v=0.25)
  elif x == 2:
    textmsg("two")
  else:
    pass
  end
  while x < 10:
    x = x + 1
    q[0] = q[0] - 0.1
  end
  def f(a, b=2):
    return a * b
  end
  set_digital_out(0, f(1) >= 2)
end
'''


def test_a_program_with_every_construct_parses():
    tree = parse(PROGRAM)
    (definition,) = tree.children
    assert definition.data == 'funcdef' and str(definition.children[0]) == 'prog'
    kinds = [s.data for s in definition.children[1].children]
    assert kinds == ['assign', 'assign', 'assign', 'if_stmt', 'while_stmt', 'funcdef', 'call_stmt']


def test_precedence_and_keywords_inside_names():
    (assign,) = parse('x = 1 + 2 * 3').children
    assert assign.children[1].data == 'binop' and str(assign.children[1].children[1]) == '+'
    # Keywords are whole words: these are plain names.
    for name in ('globalx', 'local_y', 'endx', 'iffy', 'p2'):
        (statement,) = parse(f'{name} = 1').children
        assert str(statement.children[0].children[0]) == name
    (scoped,) = parse('local y = 1').children
    assert str(scoped.children[0]) == 'local'


def test_a_secondary_program_and_bare_statements():
    assert parse('sec s():\n  set_digital_out(1, True)\nend').children[0].data == 'secdef'
    assert [s.data for s in parse('set_digital_out(0, True)\ntextmsg("x")').children] == ['call_stmt'] * 2


@pytest.mark.parametrize('source, line, column, reason', [
    ('x = ', 1, 5, 'unexpected the end of the program'),
    ('movej([0,0,0,0,0,0]', 1, 20, "expected one of: ')', ','"),
    ('def f():\n  x = 1\n', 2, 8, 'unexpected the end of the program'),
    ('x = 1 $ 2', 1, 7, "unexpected character '$'"),
    ('if x\n  y = 1\nend', 2, 3, "unexpected 'y'; expected one of: "),
    ('thread t(a):\n  sync()\nend', 1, 10, "unexpected 'a'; expected one of: ')'"),  # a thread takes no arguments
])
def test_what_does_not_compile_is_refused_with_line_column_and_reason(source, line, column, reason):
    with pytest.raises(ScriptError) as caught:
        parse(source)
    assert (caught.value.line, caught.value.column) == (line, column)
    assert f'line {line}, column {column}' in str(caught.value) and reason in str(caught.value)
