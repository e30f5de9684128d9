# Quick start: `make run` (FRF of the default rig) and `make test` (the test suite).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CASE ?= rigs/sdof_jenkins.toml

.PHONY: run test stress bench rigs rig-studies setup clean

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

# regenerate the rigs' model files (one script per rig, listed in rigs/make_all.py)
rigs: $(STAMP)
	$(BIN)/python rigs/make_all.py

# the rigs' studies: figures in rigs/figures, tables in rigs/out (several minutes)
rig-studies: $(STAMP)
	$(BIN)/python rigs/make_all.py --studies

bench: $(STAMP)
	$(BIN)/python benchmarks/time_vs_error.py

# every rig's document: figures and tables (each rigs/make_*.py regenerates one rig)
rigs: $(STAMP)
	set -e; for f in rigs/make_*.py; do echo "== $$f"; $(BIN)/python $$f; done

clean:
	rm -rf out .pytest_cache
