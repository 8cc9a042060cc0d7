# pkdyn: two entry points, each working on a fresh machine with python3 and make.
#   make demo   -- size the motors of the default DELTA 580 on the Adept cycle
#   make test   -- lint, type-check and run the whole test suite
#   make bench  -- benchmarks (figures recorded in bench/results.md and docs/guide/benchmarks.md)
#   make docs   -- the user guide, API reference and executed notebooks in docs/_build/html
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DOCS_STAMP := $(VENV)/.docs-installed
CHROMIUM ?= /usr/bin/chromium

.PHONY: demo test lint browser bench urdf docs clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/pkdyn demo

lint: $(STAMP)
	$(VENV)/bin/ruff check pkdyn solvers tests bench docs/_ext docs/conf.py
	$(VENV)/bin/ruff format --check pkdyn solvers tests bench docs/_ext docs/conf.py
	$(VENV)/bin/mypy

# Headless Chromium for the viewer's browser test (tests/test_viewer.py skips, saying why, when it
# cannot be installed: not root, no apt-get, or no package repository reachable).
browser:
	@if [ ! -x $(CHROMIUM) ] && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  echo "installing Debian chromium (headless browser test of the viewer)"; \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
	    --no-install-recommends chromium; } >/dev/null 2>&1 \
	    || echo "chromium could not be installed: the browser test will be skipped"; \
	fi

# two test processes (pytest-xdist): the suite takes about 7 min on two cores instead of 12;
# `$(PY) -m pytest tests/test_x.py` still runs one file in one process
test: lint browser
	$(PY) -m pytest -q -n 2

urdf: $(STAMP)
	for r in $$($(PY) -c "import pkdyn.library as l; print(' '.join(l.FAMILIES))"); do \
	  $(VENV)/bin/pkdyn urdf $$r -o urdf/$$r.urdf; done

bench: $(STAMP)
	$(PY) bench/run.py

# the docs extra (Sphinx, myst-nb, furo) on top of the development install
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e ".[dev,docs]"
	touch $(DOCS_STAMP)

# warnings are errors (all reported); the notebooks are executed (PKDYN_DOCS_EXECUTE=off: not)
docs: $(DOCS_STAMP)
	rm -rf docs/_autosummary
	$(VENV)/bin/sphinx-build -q -W --keep-going -b html docs docs/_build/html
	@echo "user guide, API reference and notebooks: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache docs/_build docs/_autosummary docs/notebooks \
	  docs/_generated
