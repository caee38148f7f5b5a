# Two commands: `make demo` and `make test`. Both create .venv on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
DEMO_DIR ?= demo-output

.PHONY: demo test test-slow lint bench convergence clean

# pip compiles every module's bytecode at install, one file after another (about 45 s of
# a fresh install). Without bytecode (pip's --no-compile with PYTHONDONTWRITEBYTECODE set,
# as on this project's machines) every process compiled NumPy, SciPy and pandas again at
# import (6.0 s against 1.9 s to import blockid's fitting stack). So: install without it,
# then compile the environment's modules on every core at once (compileall -j 0: 28 s
# against pip's ~45 s; a module that does not compile only keeps its source), less the
# packages' own test suites, which nothing imports (2 640 of 7 223 files: 13.4 s, and
# 12.2 s more with them).
SITE = $$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --no-compile -e ".[test]"
	$(BIN)/python -m compileall -q -j 0 -x '/tests/' "$(SITE)" src > /dev/null || true
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/blockid demo --plot $(DEMO_DIR) --force

# One BLAS and numba thread per test worker: with two workers on two cores, each
# worker's BLAS threads spun against the other's (CPU time 7 min 47 s, 5 min 9 s alone).
# PYTHONDONTWRITEBYTECODE (set on this project's machines) also stops pytest from caching
# its rewritten test modules: each worker rewrote every assert of every test file on every
# run (7 of its 16 s of collection); unset for the tests, the second run reads the cache.
TEST_ENV := OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMBA_NUM_THREADS=1 \
            PYTHONDONTWRITEBYTECODE=

# The tests on every core (pytest-xdist), without the long studies (marked slow); an idle
# worker takes queued tests from the busy one (worksteal), so no core waits at the end...
test: $(STAMP)
	$(TEST_ENV) $(BIN)/python -m pytest -q -n auto --maxprocesses 4 --dist worksteal -m "not slow"

# ...which CI runs too (.ci/run): reproductions over many seeds, convergence runs.
test-slow: $(STAMP)
	$(TEST_ENV) $(BIN)/python -m pytest -q -n auto --maxprocesses 4 --dist worksteal -m slow

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_rls.py --write-docs
	$(BIN)/python benchmarks/bench_simulation_error.py --write-docs
	$(BIN)/python benchmarks/bench_key_term.py --write-docs
	$(BIN)/python benchmarks/bench_state_space.py --write-docs

clean:
	rm -rf $(VENV) build dist src/*.egg-info

convergence: $(STAMP)
	$(BIN)/python benchmarks/convergence_study.py

# Mutation benchmark of the core (about an hour on two cores; not part of `make test`).
# Runs on a snapshot of HEAD in a temporary folder; see docs/testing.md.
.PHONY: mutate
mutate: $(STAMP)
	test -x $(BIN)/mutmut || $(BIN)/python -m pip install --quiet -e ".[test,mutation]"
	nice -n 10 $(BIN)/python mutation/run.py
	nice -n 10 $(BIN)/python mutation/kernels.py
