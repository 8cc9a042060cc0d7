# pkdyn: two entry points, each working on a fresh machine with python3 and make.
#   make demo   -- size the motors of the default DELTA 580 on the Adept cycle
#   make test   -- lint, type-check and run the whole test suite
#   make bench  -- benchmarks (figures recorded in bench/results.md and docs/guide/benchmarks.md)
#   make docs   -- the user guide, API reference and executed notebooks in docs/_build/html
# Installs take the exact versions the suite was tested with (constraints.txt):
#   make latest       -- the latest releases instead, in .venv-latest, and the suite there
#   make constraints  -- constraints.txt from .venv-latest (after `make latest` passed)
#   make test-kernel  -- the numeric tests again under another OpenBLAS kernel (.ci/run)
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DOCS_STAMP := $(VENV)/.docs-installed
CONSTRAINTS := constraints.txt
LATEST := .venv-latest
CHROMIUM ?= /usr/bin/chromium

.PHONY: demo test lint browser bench urdf docs clean latest constraints test-kernel

$(STAMP): pyproject.toml $(CONSTRAINTS)
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c $(CONSTRAINTS) -e ".[dev]"
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

# The numeric tests of the dynamics, precision, calibration and identification once more under
# an OpenBLAS kernel other than the machine's own (.ci/other_kernel.py: Haswell, or SkylakeX /
# Sandybridge on a Haswell machine): a test whose assertion depends on the kernel's rounding
# fails on some machine. About 2 min on two idle cores (4 min at a load average of 8).
KERNEL_TESTS = tests/test_dynamics.py tests/test_forward_dynamics.py \
  tests/test_forward_dynamics_steps.py tests/test_conditioning.py tests/test_control_step.py \
  tests/test_inverse_dynamics.py tests/test_inverse_dynamics_paths.py \
  $(filter-out tests/test_precision_inputs.py,$(wildcard tests/test_precision_*.py)) \
  tests/test_coupled_precision.py tests/test_calibration.py tests/test_identification*.py
test-kernel: $(STAMP)
	@kernel=$$($(PY) .ci/other_kernel.py); \
	if [ -z "$$kernel" ]; then echo "no other OpenBLAS kernel runs on this CPU: skipped"; exit 0; fi; \
	echo "the numeric tests under OPENBLAS_CORETYPE=$$kernel"; \
	OPENBLAS_CORETYPE=$$kernel $(PY) -m pytest -q -n 2 $(KERNEL_TESTS)

# The latest releases of every dependency (not the tested versions of constraints.txt), in a
# separate environment, and the whole suite there: what a user installing today gets. Not part
# of CI (a new release must not fail a submission); run it before refreshing the constraints.
latest:
	test -x $(LATEST)/bin/python || $(PYTHON) -m venv $(LATEST)
	$(LATEST)/bin/python -m pip install --quiet --upgrade pip
	$(LATEST)/bin/python -m pip install --quiet --upgrade --upgrade-strategy eager -e ".[dev,docs]"
	$(LATEST)/bin/python -m pip list --outdated --exclude-editable || true
	$(LATEST)/bin/python -m pytest -q -n 2

# The exact versions of the latest environment (after `make latest` passed) as the new tested set
constraints:
	test -x $(LATEST)/bin/python || { echo "run make latest first"; exit 1; }
	{ echo "# The versions pkdyn is tested with: pip install -c constraints.txt -e '.[dev,docs]'"; \
	  echo "# (everything pip installs for .[dev,docs] on Python 3.11, Linux x86_64; make constraints)"; \
	  $(LATEST)/bin/python -m pip freeze --exclude-editable | grep -iv '^pkdyn'; } > $(CONSTRAINTS).tmp
	mv $(CONSTRAINTS).tmp $(CONSTRAINTS)

urdf: $(STAMP)
	for r in $$($(PY) -c "import pkdyn.library as l; print(' '.join(l.FAMILIES))"); do \
	  $(VENV)/bin/pkdyn urdf $$r -o urdf/$$r.urdf; done

bench: $(STAMP)
	$(PY) bench/run.py

# the docs extra (Sphinx, myst-nb, furo) on top of the development install
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -c $(CONSTRAINTS) -e ".[dev,docs]"
	touch $(DOCS_STAMP)

# warnings are errors (all reported); the notebooks are executed (PKDYN_DOCS_EXECUTE=off: not)
docs: $(DOCS_STAMP)
	rm -rf docs/_autosummary
	$(VENV)/bin/sphinx-build -q -W --keep-going -b html docs docs/_build/html
	@echo "user guide, API reference and notebooks: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) $(LATEST) .pytest_cache .mypy_cache .ruff_cache docs/_build docs/_autosummary docs/notebooks \
	  docs/_generated
