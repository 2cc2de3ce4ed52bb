# The two README commands (and the benchmarks). Each first runs the idempotent setup.
PYTHON ?= python3
VENV_PY := .venv/bin/python

.PHONY: setup demo test bench clean

setup:
	@$(PYTHON) tools/bootstrap.py

demo: setup
	@.venv/bin/bearing-graph --out out/demo

test: setup
	@$(VENV_PY) -m pytest tests

bench: setup
	@$(VENV_PY) tools/bench.py --out out/bench.md

clean:
	rm -rf ros_ws/build ros_ws/install ros_ws/log out
