# Quick start: `make run` (FRF of the default rig) and `make test` (the test suite).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CASE ?= rigs/sdof_jenkins.toml

.PHONY: run test stress bench rigs rig-models setup clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	@echo "compiling the numerical kernels of Jenkins and friction3d contacts (about 45 s, once)"
	$(BIN)/hbm frf rigs/sdof_jenkins.toml -o $(VENV)/warmup > /dev/null 2>&1
	$(BIN)/hbm frf rigs/inclined_contact.toml -o $(VENV)/warmup > /dev/null 2>&1
	$(BIN)/python -c "from elements.friction2d_events import compile_kernels; compile_kernels()"
	@echo "compiling the time integrator and its period map (about 55 s, once: Floquet checks, time fill)"
	$(BIN)/hbm timesim rigs/sdof_jenkins.toml --freq-hz 30 --floquet -o $(VENV)/warmup > /dev/null 2>&1
	touch $(STAMP)

setup: $(STAMP)

run: $(STAMP)
	$(BIN)/hbm frf $(CASE) -o out

# one BLAS thread: the tests' matrices are small, and a threaded BLAS on busy cores slows
# them by an order of magnitude; two worker processes (pytest-xdist), one per core
test: $(STAMP)
	OPENBLAS_NUM_THREADS=1 $(BIN)/python -m pytest tests -n 2

# the full stress matrix (minutes; STRESS_JOBS=n worker processes, default: all cores), one
# BLAS thread per worker (two workers with threaded BLAS: 244 s, one thread each: 86 s)
stress: $(STAMP)
	OPENBLAS_NUM_THREADS=1 $(BIN)/python -m pytest tests/stress -m stress

# every figure and table of the rig documents, and the rigs' model files (tens of minutes;
# the scripts are listed per rig in rigs/make_all.py)
rigs: $(STAMP)
	$(BIN)/python rigs/make_all.py --studies

# the rigs' model files only
rig-models: $(STAMP)
	$(BIN)/python rigs/make_all.py

bench: $(STAMP)
	$(BIN)/python benchmarks/time_vs_error.py

# numba caches too: a kernel cached in one file keeps an inlined law from another file
# until its own file changes (after editing a law, `make clean`)
clean:
	rm -rf out .pytest_cache
	find hbm elements continuation -name '*.nbi' -delete -o -name '*.nbc' -delete
