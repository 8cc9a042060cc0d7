# pkdyn: two entry points, each working on a fresh machine with python3 and make.
#   make demo   -- size the motors of the default DELTA 580 on the Adept cycle
#   make test   -- lint, type-check and run the whole test suite
#   make bench  -- benchmarks (figures recorded in README.md)
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench urdf clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/pkdyn demo

lint: $(STAMP)
	$(VENV)/bin/ruff check pkdyn solvers tests bench
	$(VENV)/bin/ruff format --check pkdyn solvers tests bench
	$(VENV)/bin/mypy

test: lint
	$(PY) -m pytest -q

urdf: $(STAMP)
	for r in delta gough_stewart planar_3rrr five_bar tripod; do $(VENV)/bin/pkdyn urdf $$r -o urdf/$$r.urdf; done

bench: $(STAMP)
	$(PY) bench/run.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
