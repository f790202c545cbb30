"""The tree shows the layers: every import of ur_sim_driver by ur_sim_driver goes to the same layer or one below;
ur_glue_planner stands on the shared ground only (ur_common and ur_sim_driver's description), never on the
simulator's runtime; ur_common imports neither package; and no package has an import cycle.

Read from the source with ``ast`` (every import statement, also inside functions and ``if TYPE_CHECKING``), so a
lazy import cannot hide an upward dependency. The order is the one ``ur_sim_driver/__init__.py`` documents.
"""
import ast
import re
from pathlib import Path

import pytest

import ur_common
import ur_glue_planner
import ur_sim_driver

# lowest first
ORDER = ('description', 'physics', 'robot', 'motion', 'urscript', 'gateway', 'controllers', 'ports', 'ros')
# the modules at the top: importable by all, importing nothing of ours
BASE = ('errors',)
SHARED = ('description',)  # the layer of ur_sim_driver that ur_glue_planner may import (and ur_common)
ROOT = Path(ur_sim_driver.__file__).parent
PLANNER = Path(ur_glue_planner.__file__).parent
COMMON = Path(ur_common.__file__).parent


def _modules(root: Path = ROOT) -> list[Path]:
    return sorted(p for p in root.rglob('*.py') if '__pycache__' not in p.parts)


def _layer(module: str) -> int:
    """The layer of a dotted module name below ur_sim_driver (BASE modules: -1)."""
    first = module.split('.')[1] if '.' in module else ''
    if first in BASE:
        return -1
    if first not in ORDER:
        raise AssertionError(f'ur_sim_driver.{first} is in no layer; the layers are {", ".join(ORDER)}')
    return ORDER.index(first)


def _imports(path: Path, package: str = 'ur_sim_driver') -> list[tuple[int, str]]:
    """(line, module) of each module of `package` imported by the file at `path`."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.startswith(package + '.')]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or '').startswith(package):
            if node.module == package or node.module.count('.') == 1:  # from package[.sub] import x
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
        named = set(re.findall(r'\w+', said))  # words: 'ports' is not named by 'Imports'
        for other in below:
            assert other in named, f'{layer}: its docstring does not say that it may import {other}'
        for other in ORDER[ORDER.index(layer) + 1:]:
            assert other not in named, f'{layer}: its docstring names {other}, a layer above it, as importable'


@pytest.mark.parametrize('path', _modules(PLANNER), ids=lambda p: str(p.relative_to(PLANNER)))
def test_the_planner_imports_only_the_shared_ground(path):
    for line, module in _imports(path):
        first = module.split('.')[1]
        assert first in SHARED, (f'ur_glue_planner/{path.relative_to(PLANNER)}:{line} imports {module}, '
                                 f"the simulator's runtime; it may import ur_sim_driver's {', '.join(SHARED)} "
                                 'and ur_common')


@pytest.mark.parametrize('path', _modules(COMMON), ids=lambda p: str(p.relative_to(COMMON)))
def test_the_shared_ground_imports_neither_package(path):
    for package in ('ur_sim_driver', 'ur_glue_planner'):
        found = _imports(path, package)
        assert not found, f'ur_common/{path.relative_to(COMMON)}:{found[0][0]} imports {found[0][1]}'


def _module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix('').parts
    return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


@pytest.mark.parametrize('root', (ROOT, PLANNER, COMMON), ids=lambda r: r.name)
def test_no_import_cycle(root):
    names = {_module_name(p, root): p for p in _modules(root)}
    graph = {}
    for name, path in names.items():
        targets = set()
        for _, module in _imports(path, root.name):
            # `from pkg.sub import name` names a module or something in pkg.sub: take the longest module that exists
            while module not in names and '.' in module:
                module = module.rsplit('.', 1)[0]
            if module != name and module in names and not names[module].name == '__init__.py':
                targets.add(module)
        graph[name] = targets
    done: set[str] = set()

    def visit(name: str, trail: list[str]) -> None:
        if name in trail:
            raise AssertionError(f'import cycle: {" -> ".join(trail[trail.index(name):] + [name])}')
        if name in done:
            return
        for target in sorted(graph[name]):
            visit(target, trail + [name])
        done.add(name)

    for name in sorted(graph):
        visit(name, [])
