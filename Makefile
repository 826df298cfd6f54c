# Quick start targets. Each one sets everything up from a clean clone, then runs.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup demo test lint bench clean

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

## Run the main job: the whole chain on the built-in example.
demo: $(STAMP)
	$(BIN)/ruledrobot demo --out out/demo

## Run the whole test suite (what CI runs).
test: $(STAMP)
	$(BIN)/ruff check ruledrobot tests scripts
	$(BIN)/pytest -q

lint: $(STAMP)
	$(BIN)/ruff check ruledrobot tests scripts

bench: $(STAMP)
	$(BIN)/pip install --quiet -e '.[test,bench]'
	$(BIN)/python scripts/bench_geometry.py

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache
