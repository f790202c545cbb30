"""Run every benchmark module that exists (or those named: ``python -m bench sim tricks``) and write its JSON under
out/bench/."""
import importlib
import json
import pkgutil
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / 'out' / 'bench'


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    names = [m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)]) if m.name.startswith('bench_')]
    if sys.argv[1:]:
        unknown = sorted(set(sys.argv[1:]) - {n.removeprefix('bench_') for n in names})
        if unknown:
            print(f'bench: no benchmark {", ".join(unknown)}; choose from '
                  f'{", ".join(sorted(n.removeprefix("bench_") for n in names))}')
            return 2
        names = [n for n in names if n.removeprefix('bench_') in sys.argv[1:]]
    if not names:
        print('bench: no benchmarks yet')
        return 0
    for name in sorted(names):
        module = importlib.import_module(f'bench.{name}')
        result = module.run()
        path = OUT / f'{name.removeprefix("bench_")}.json'
        path.write_text(json.dumps(result, indent=2))
        print(f'bench: wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
