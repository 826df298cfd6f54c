# Quick start targets. Each one sets everything up from a clean clone, then runs.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# pytest with bytecode written (PYTHONDONTWRITEBYTECODE empty is unset for Python): the
# package's modules and the assertion-rewritten test modules are compiled once and read
# back by every later process (xdist workers, the real-time run, the next make test);
# collecting the suite took 7-9 s of CPU a process without, 4-5 s with (issue 34)
PYTEST := PYTHONDONTWRITEBYTECODE= $(BIN)/pytest

.PHONY: setup demo test test-fast lint bench clean

# uv (from PyPI, into the venv) installs the package and its dependencies: it downloads
# and compiles in parallel (a fresh venv here: 26 s against pip's 41 s, bytecode compiled
# either way; without it a test run's workers compile what they import, and the first
# stage took 10-24 s longer)
UV := $(BIN)/uv pip install --python $(BIN)/python --quiet --compile-bytecode

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet uv
	$(UV) -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

## Run the main job: the whole chain on the built-in example.
demo: $(STAMP)
	$(BIN)/ruledrobot demo --out out/demo

## Run the whole test suite (what CI runs): the tests that are not real-time on both
## cores (pytest-xdist; a module's tests on one worker, so its module fixtures are built
## once), then the real-time ones (emulator streams) apart from them, in three groups of
## whole modules: they mostly wait for the emulator's clock (their tolerances are sized
## for a loaded 2-core machine; README, "Development").  The longest modules are handed
## out first (tests/conftest.py, LONGEST_FIRST; xdist's own order is by number of tests).
test: $(STAMP)
	$(BIN)/ruff check ruledrobot tests scripts
	$(PYTEST) -q -n 2 --dist loadscope --no-loadscope-reorder -m "not realtime"
	$(PYTEST) -q -n 3 --dist loadfile --no-loadscope-reorder -m realtime

## The edit loop: ruff and the fast tests on both cores (no real-time streams, no slow
## tests: SLOW_MODULES and SLOW_TESTS in tests/conftest.py, chosen by measured
## durations); CI runs `make test`.
test-fast: $(STAMP)
	$(BIN)/ruff check ruledrobot tests scripts
	$(PYTEST) -q -n 2 -m "not realtime and not slow"

lint: $(STAMP)
	$(BIN)/ruff check ruledrobot tests scripts

bench: $(STAMP)
	$(UV) -e '.[test,bench]'
	$(BIN)/python scripts/bench_geometry.py

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache
