# The two README commands (and the benchmarks, lint, a fast unit loop). Each first runs the
# idempotent setup, for ROS 2 $(ROS_DISTRO): Jazzy unless e.g. `ROS_DISTRO=kilted make test`
# (tools/bootstrap.py reads ROS_DISTRO; switching rebuilds .venv/ and ros_ws/).
PYTHON ?= python3
VENV_PY := .venv/bin/python

.PHONY: setup full-install demo test unit lint fuzz bench accuracy false-alarm-matrix false-alarms trend soak cli-test stops stop-repeats speed-data speed-tracking speed-accuracy clean

setup:
	@$(PYTHON) tools/bootstrap.py

demo: setup
	@.venv/bin/bearing-graph --out out/demo

# the real ros2 CLI over the wheels (../shared/ros2-cli) and ros_ws/ built in it as a full ROS 2 install
# builds it (out/ros2-cli, out/full-install; redone only when inputs change); skipped without ../shared/ros2-cli
full-install: setup
	@$(VENV_PY) tools/full_ros_install.py || [ $$? -eq 3 ]

test: setup
	@$(VENV_PY) -m pytest tests

# the real-CLI tests (tests/ros/test_ros2_cli.py) in the full install: ros2 launch/run/topic/param/interface
# and Ctrl-C (10 stops of the fleet launch); CI (.ci/run) runs it after `make test` (its first build: 8 min)
cli-test: setup full-install
	@BEARING_REAL_CLI=1 $(VENV_PY) -m pytest tests/ros/test_ros2_cli.py

# the tests without DDS (pure-Python cores, files, CLIs): the fast loop
unit: setup
	@$(VENV_PY) -m pytest tests/unit

lint: setup
	@.venv/bin/ruff check .

# the property-based tests with new random cases, FUZZ_CASES per property (the suite: 300, fixed)
FUZZ_CASES ?= 3000
fuzz: setup
	@BEARING_FUZZ_CASES=$(FUZZ_CASES) $(VENV_PY) -m pytest tests/unit/test_fuzz_inputs.py --hypothesis-profile=explore \
		-o timeout=1800 -o faulthandler_timeout=300

# each benchmark also writes its tables into the docs' generated blocks (benchmarks/doc_tables.py)
bench: setup
	@$(VENV_PY) benchmarks/run.py --out out/bench.md --docs docs/benchmarks.md

# decisions on every development recording, against the textbook baseline, with ablations,
# times to decision and detection curves (-> out/accuracy.md, out/detection_curves.png), then the false-alarm matrix
# and the accuracy under changing speed
accuracy: setup
	@$(VENV_PY) benchmarks/accuracy_report.py --out out/accuracy.md --figure out/detection_curves.png --docs docs/results.md
	@$(MAKE) --no-print-directory false-alarm-matrix
	@$(MAKE) --no-print-directory speed-accuracy

# every healthy recording with every catalog bearing and bearings whose fault orders are (near) shaft
# harmonics, told its speed and 7 % off, as recorded, without its 1x family and with a foreign envelope
# line: alarms of ours and of the baseline (-> out/false_alarm_matrix.md); MATRIX_JOBS worker processes
MATRIX_JOBS ?= 1
false-alarm-matrix: setup
	@$(VENV_PY) benchmarks/false_alarm_matrix.py --jobs $(MATRIX_JOBS) --out out/false_alarm_matrix.md --docs docs/results.md

# false alarms of the live decision on FALSE_ALARM_HOURS (default 10) of simulated healthy signal
# and on looped healthy recordings -> out/false_alarms.md
FALSE_ALARM_HOURS ?= 10
false-alarms: setup
	@$(VENV_PY) benchmarks/false_alarms.py --hours $(FALSE_ALARM_HOURS) --out out/false_alarms.md --docs docs/results.md

# test data for changing speed: simulated ramps and the development recordings warped along the same
# speed profiles, as .npz files with shaft_speed -> out/speed_ramps/ (README, "Changing speed")
speed-data: setup
	@$(VENV_PY) -m benchmarks.speed_ramps --out out/speed_ramps

# detection against fault amplitude on ramps of ±10, ±20, ±40 % over 10 s (synthetic and warped development
# recordings) with a tachometer, tacho-less and the constant-speed decision, and false alarms on healthy ramps
# -> out/speed_accuracy.md, out/speed_accuracy.png (SPEED_ACCURACY_ARGS=--quick: a subset in about 1.5 min)
speed-accuracy: setup
	@$(VENV_PY) -m benchmarks.speed_accuracy --out out/speed_accuracy.md --figure out/speed_accuracy.png \
		--docs docs/changing-speed.md $(SPEED_ACCURACY_ARGS)

# accuracy of the tacho-less speed tracking on synthetic, simulated and warped ramps -> out/speed_tracking.md
speed-tracking: setup
	@$(VENV_PY) -m benchmarks.speed_tracking --out out/speed_tracking.md

# early warning on the six FEMTO lives (against the textbook rule) and on healthy recordings -> out/trend.md
trend: setup
	@$(VENV_PY) benchmarks/trend_report.py --out out/trend.md --docs docs/health.md

# the whole graph at real time for SOAK_MINUTES (default 30) -> out/soak.md
SOAK_MINUTES ?= 30
soak: setup
	@$(VENV_PY) benchmarks/soak.py --minutes $(SOAK_MINUTES) --out out/soak.md --docs docs/robustness.md

# Ctrl-C to the starved `ros2 launch` of the monitoring graph, STOPS times (default 20): 0 stalls expected;
# the starving adds busy loops until the simulator is behind real time, a slow stop prints native stacks
STOPS ?= 20
stops: setup full-install
	@BEARING_REAL_CLI=1 BEARING_STOPS=$(STOPS) $(VENV_PY) -m pytest tests/ros/test_ros2_cli.py -k starved_monitor -q -s

# SIGINT to three observers at once beside the simulator, pinned to one core beside two busy loops,
# STOP_ROUNDS times (default 34: 102 stops, about 15 min): every stop must exit 0 within the stall watchdog
STOP_ROUNDS ?= 34
stop-repeats: setup
	@BEARING_STOP_REPEATS=$(STOP_ROUNDS) $(VENV_PY) -m pytest tests/ros/test_stop_repeats.py -q -s -o timeout=7200

clean:
	rm -rf ros_ws/build ros_ws/install ros_ws/log out
