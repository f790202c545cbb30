# See README.md. Every target sets up what it needs first (idempotent, seconds when done).
SHELL := /bin/bash
ENV := source scripts/env.bash &&

.PHONY: setup demo parts test lint bench clean

setup:
	@bash scripts/setup.sh

demo: setup
	@$(ENV) bash scripts/demo.sh

parts: setup
	@$(ENV) bash scripts/parts.sh

test: setup
	@$(ENV) ruff check .
	@$(ENV) python -m pytest test -n 3 --dist loadfile --no-loadscope-reorder

lint: setup
	@$(ENV) ruff check .

bench: setup
	@$(ENV) python -m bench

clean:
	rm -rf build install log out .venv
