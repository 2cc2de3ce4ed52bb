# The two README commands (and the benchmarks, lint, a fast unit loop). Each first runs the
# idempotent setup, for ROS 2 $(ROS_DISTRO): Jazzy unless e.g. `ROS_DISTRO=kilted make test`
# (tools/bootstrap.py reads ROS_DISTRO; switching rebuilds .venv/ and ros_ws/).
PYTHON ?= python3
VENV_PY := .venv/bin/python

.PHONY: setup demo test unit lint bench accuracy soak clean

setup:
	@$(PYTHON) tools/bootstrap.py

demo: setup
	@.venv/bin/bearing-graph --out out/demo

test: setup
	@$(VENV_PY) -m pytest tests

# the tests without DDS (pure-Python cores, files, CLIs): the fast loop
unit: setup
	@$(VENV_PY) -m pytest tests/unit

lint: setup
	@.venv/bin/ruff check .

bench: setup
	@$(VENV_PY) benchmarks/run.py --out out/bench.md

# decisions on every development recording, against the textbook baseline, with ablations
accuracy: setup
	@$(VENV_PY) benchmarks/accuracy_report.py --out out/accuracy.md

# the whole graph at real time for SOAK_MINUTES (default 30) -> out/soak.md
SOAK_MINUTES ?= 30
soak: setup
	@$(VENV_PY) benchmarks/soak.py --minutes $(SOAK_MINUTES) --out out/soak.md

clean:
	rm -rf ros_ws/build ros_ws/install ros_ws/log out
