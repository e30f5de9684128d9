# Quick start: `make run` (FRF of the default rig) and `make test` (the test suite).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CASE ?= rigs/sdof_jenkins.toml

.PHONY: run test stress bench setup clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

run: $(STAMP)
	$(BIN)/hbm frf $(CASE) -o out

test: $(STAMP)
	$(BIN)/python -m pytest tests

# the full stress matrix (minutes; STRESS_JOBS=n worker processes, default: all cores)
stress: $(STAMP)
	$(BIN)/python -m pytest tests/stress -m stress

bench: $(STAMP)
	$(BIN)/python benchmarks/time_vs_error.py

clean:
	rm -rf out .pytest_cache
