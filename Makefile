# rattle_lab developer entry points.  Only Python 3.11+ and make are needed.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-test
STAMP_RUN := $(VENV)/.installed
STAMP_DEV := $(VENV)/.installed-dev
STAMP_DOCS := $(VENV)/.installed-docs

.PHONY: demo test test-fast test-foreign lint docs bench install clean reference-images

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# an editable install leaves the package's modules uncompiled, and where PYTHONDONTWRITEBYTECODE
# is set every process compiles them again (about 1 s a `rattle-lab` call): compile them once
$(STAMP_RUN): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	$(BIN)/python -m compileall -q rattle_lab
	$(BIN)/python -m rattle_lab._warmup
	touch $@

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test]"
	$(BIN)/python -m compileall -q rattle_lab
	$(BIN)/python -m rattle_lab._warmup
	touch $@ $(STAMP_RUN)

$(STAMP_DEV): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test,dev]"
	touch $@ $(STAMP) $(STAMP_RUN)

$(STAMP_DOCS): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $@

install: $(STAMP_RUN)

## make demo: simulate the embedded default scene, then ingest, fit and report
demo: $(STAMP_RUN)
	$(BIN)/rattle-lab demo --out demo_out

## make test: the whole test suite and every docstring example (doctests), on TEST_JOBS
## processes (pytest-xdist; TEST_JOBS=0 runs it in this one), a whole file to a process
## (its fixtures are built once)
TEST_JOBS ?= 2
XDIST = -n $(TEST_JOBS) --dist loadfile
PYTEST_ARGS ?=
test: $(STAMP)
	$(BIN)/python -m pytest -q $(XDIST) $(PYTEST_ARGS)

## make test-fast: the suite without the tests marked slow (over about 8 s each)
test-fast: $(STAMP)
	$(BIN)/python -m pytest -q $(XDIST) -m "not slow" $(PYTEST_ARGS)

## make test-foreign: the numerically sensitive tests (marker numerics) again as another
## x86-64 machine computes them: OpenBLAS's Nehalem kernels (which every x86-64 CPU runs)
## and numba code for a generic CPU, compiled into a numba cache folder of its own
FOREIGN_ENV = OPENBLAS_CORETYPE=Nehalem NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=$(CURDIR)/.numba-generic
test-foreign: $(STAMP)
	$(FOREIGN_ENV) $(BIN)/python -m rattle_lab._warmup
	$(FOREIGN_ENV) $(BIN)/python -m pytest -q $(XDIST) -m numerics -p no:cacheprovider \
		$(PYTEST_ARGS)

## make lint: ruff (style, bugs), mypy (types of the package) and the docs build (make docs)
lint: $(STAMP_DEV) $(STAMP_DOCS)
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(MAKE) docs

## make docs: the guide and the API reference (Sphinx, warnings are errors) in docs/_build/html
docs: $(STAMP_DOCS)
	$(BIN)/python -m sphinx -W --keep-going -E -b html -q docs docs/_build/html

## make bench: every benchmark table (not part of CI)
bench: $(STAMP)
	for b in benchmarks/*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info demo_out .pytest_cache .mypy_cache .ruff_cache docs/_build \
		.numba-generic

## make reference-images: rewrite the report tests' reference images (tests/data/report_pages)
## after an intended change to a report page; look at them before committing.  No test does it.
reference-images: $(STAMP)
	$(BIN)/python tests/regen_reference_images.py
