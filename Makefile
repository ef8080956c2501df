PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP_DEMO := $(VENV)/.demo-installed
STAMP_TEST := $(VENV)/.test-installed
STAMP_BENCH := $(VENV)/.bench-installed
# pyNastran holds numpy < 2: the NASTRAN importer's tests run in their own environment, so the
# main one has the numpy that `make demo` gives users
VENV_NASTRAN := .venv-nastran
BIN_NASTRAN := $(VENV_NASTRAN)/bin
STAMP_NASTRAN := $(VENV_NASTRAN)/.test-installed

.PHONY: demo test lint docs bench bench-scale clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(BIN_NASTRAN)/python:
	$(PYTHON) -m venv $(VENV_NASTRAN)
	$(BIN_NASTRAN)/python -m pip install --quiet --upgrade pip

$(STAMP_DEMO): pyproject.toml src/contactqp/kernels/compiled.pyx | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[demo]"
	touch $@

$(STAMP_TEST): pyproject.toml src/contactqp/kernels/compiled.pyx | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $@

$(STAMP_NASTRAN): pyproject.toml src/contactqp/kernels/compiled.pyx | $(BIN_NASTRAN)/python
	$(BIN_NASTRAN)/python -m pip install --quiet -e ".[test-nastran]"
	touch $@

$(STAMP_BENCH): pyproject.toml src/contactqp/kernels/compiled.pyx | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test,bench]"
	touch $@

demo: $(STAMP_DEMO)
	@mkdir -p out/demo
	$(BIN)/contactqp rod --plot out/demo/rod.png --vtu out/demo/rod.vtu
	$(BIN)/contactqp rod --json > out/demo/rod.json
	$(BIN)/contactqp springs --n 3 --stiffness 1 --mu 0.2 --mass 2 --g 10 --force 3,6,9,14 --plot out/demo/springs.png
	$(BIN)/contactqp solve examples/problems/two_springs.toml --out out/demo/two_springs
	$(BIN)/contactqp solve examples/problems/block_on_floor.toml --out out/demo/block_on_floor
	@echo "demo outputs in out/demo/: rod.png, rod.vtu (ParaView), rod.json, springs.png, two_springs/, block_on_floor/"

# every test runs: the main run (numpy of `demo`) deselects exactly the `nastran` marker, which
# the second run selects (pytest's "deselected" and "passed" counts show both)
# lint first: a ruff or mypy finding fails `make test`
test: lint docs $(STAMP_NASTRAN)
	@$(BIN)/python -c "import numpy; print('main tests on numpy', numpy.__version__)"
	$(BIN)/python -m pytest -q -m "not nastran"
	@$(BIN_NASTRAN)/python -c "import numpy; print('NASTRAN tests on numpy', numpy.__version__)"
	$(BIN_NASTRAN)/python -m pytest -q -m nastran tests/test_importers.py tests/test_assembly_nastran.py

# ruff (lint and format) and mypy, configured in pyproject.toml; the `test` extra brings them
lint: $(STAMP_TEST)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

# the documentation site, offline (no intersphinx, nothing fetched): every warning is an error
# (-W --keep-going reports them all) and every cross-reference must resolve (-n); the gallery
# runs the examples. Open docs/_build/html/index.html
docs: $(STAMP_TEST)
	$(BIN)/sphinx-build -W --keep-going -n -q -b html docs docs/_build/html
	@echo "documentation in docs/_build/html/index.html"

bench: $(STAMP_TEST)
	$(BIN)/python benchmarks/bench_frictionless.py

# matrix-free surface contact (FFT half-space) against Tamaas and ContactMechanics, one thread;
# BENCH_SCALE_ARGS=--large adds Hertz 1024^2 and rough 2048^2 (see benchmarks/README.md)
bench-scale: $(STAMP_BENCH)
	$(BIN)/python benchmarks/bench_scale.py $(BENCH_SCALE_ARGS)

clean:
	rm -rf $(VENV) $(VENV_NASTRAN) out build docs/_build docs/auto_examples docs/api/generated docs/sg_execution_times.rst src/*.egg-info src/contactqp/kernels/compiled.c src/contactqp/kernels/compiled.*.so
