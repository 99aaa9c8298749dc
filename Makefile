# Two commands do all set-up on a fresh Debian/Ubuntu machine with Python 3.11+ and PyPI:
#   make run    the main job (installs into .venv first)
#   make test   the test suite (installs into .venv first)
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# Pytest selection: CI runs the short form; `make test-all` includes the long sweeps.
PYTEST_ARGS ?= -m "not slow"

.PHONY: run test test-all bench install clean

# tf2_msgs (no PyPI wheel) built from interfaces/ into the venv once; skipped where a ROS 2
# Jazzy provides it. Needs cmake and a C/C++ compiler (Debian: apt-get install cmake g++).
TF2_MSGS := $(VENV)/.tf2_msgs
$(TF2_MSGS): requirements.txt requirements-build.txt interfaces/build.sh \
		$(wildcard interfaces/tf2_msgs/* interfaces/tf2_msgs/msg/*)
	PYTHON=$(PYTHON) interfaces/build.sh $(VENV)

$(STAMP): requirements.txt requirements-test.txt setup.py package.xml $(TF2_MSGS)
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "Python 3.11+ is needed"'
	@$(PYTHON) -m venv $(VENV) || { echo "python3 -m venv failed: apt-get install python3-venv"; exit 1; }
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements-test.txt
	touch $(STAMP)

# A plain (non-editable) install, so that .venv is a valid ament prefix for `ros2 run`.
install: $(STAMP)
	$(PY) -m pip install --quiet --no-deps --force-reinstall .

run: install
	AMENT_PREFIX_PATH=$(abspath $(VENV)) $(PY) -m youbot_dynamics main-job

test: $(STAMP)
	$(PY) -m pytest -q -n 2 --timeout 900 $(PYTEST_ARGS) test

test-all: PYTEST_ARGS =
test-all: test

bench: $(STAMP)
	$(PY) -m pip install --quiet -r requirements-bench.txt
	for b in bench/*.py; do echo "== $$b"; $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info out
