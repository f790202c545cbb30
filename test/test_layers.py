"""The tree shows the layers: every import of ur_sim_driver by ur_sim_driver goes to the same layer or one below.

Read from the source with ``ast`` (every import statement, also inside functions and ``if TYPE_CHECKING``), so a
lazy import cannot hide an upward dependency. The order is the one ``ur_sim_driver/__init__.py`` documents.
"""
import ast
from pathlib import Path

import pytest

import ur_sim_driver

ORDER = ('description', 'physics', 'robot', 'motion', 'gateway', 'controllers', 'ros')  # lowest first
BASE = ('errors', 'paths')  # the modules at the top: importable by all, importing nothing of ours
ROOT = Path(ur_sim_driver.__file__).parent


def _modules() -> list[Path]:
    return sorted(p for p in ROOT.rglob('*.py') if '__pycache__' not in p.parts)


def _layer(module: str) -> int:
    """The layer of a dotted module name below ur_sim_driver (BASE modules: -1)."""
    first = module.split('.')[1] if '.' in module else ''
    if first in BASE:
        return -1
    if first not in ORDER:
        raise AssertionError(f'ur_sim_driver.{first} is in no layer; the layers are {", ".join(ORDER)}')
    return ORDER.index(first)


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of each ur_sim_driver module imported by the file at `path`."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.startswith('ur_sim_driver.')]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or '').startswith('ur_sim_driver'):
            if node.module == 'ur_sim_driver' or node.module.count('.') == 1:  # from ur_sim_driver[.layer] import x
                found += [(node.lineno, f'{node.module}.{a.name}') for a in node.names]
            else:
                found.append((node.lineno, node.module))
        elif isinstance(node, ast.ImportFrom) and node.level > 0:
            raise AssertionError(f'{path}:{node.lineno}: relative import; name the module in full')
    return found


def test_there_are_at_most_a_handful_of_modules_at_the_top():
    top = sorted(p.stem for p in ROOT.glob('*.py') if p.stem != '__init__')
    assert top == sorted(BASE)
    assert sorted(p.name for p in ROOT.iterdir() if (p / '__init__.py').exists()) == sorted(ORDER)


@pytest.mark.parametrize('path', _modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_go_only_downwards(path):
    rel = path.relative_to(ROOT)
    own = -1 if len(rel.parts) == 1 else ORDER.index(rel.parts[0])
    for line, module in _imports(path):
        target = _layer(module)
        assert own != -1, f'{rel}:{line} imports {module}: the top modules ({", ".join(BASE)}) import nothing of ours'
        assert target <= own, (f'{rel}:{line} imports {module}, a layer above {ORDER[own]} '
                                f'(lowest first: {", ".join(ORDER)})')


def test_every_layer_says_what_lives_there_and_what_it_may_import():
    for layer in ORDER:
        doc = ast.get_docstring(ast.parse((ROOT / layer / '__init__.py').read_text()))
        assert doc, f'ur_sim_driver/{layer}/__init__.py has no docstring'
        below = ORDER[:ORDER.index(layer)]
        said = doc[doc.index('May import'):] if 'May import' in doc else doc[doc.index('Imports nothing'):]
        for other in below:
            assert other in said, f'{layer}: its docstring does not say that it may import {other}'
        for other in ORDER[ORDER.index(layer) + 1:]:
            assert other not in said, f'{layer}: its docstring names {other}, a layer above it, as importable'
