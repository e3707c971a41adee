# aggsym: everything the project needs is installed here, into .venv, from pyproject.toml.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin

.PHONY: install test clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# runtime only (sympy, numpy, jinja2, pyyaml)
$(VENV)/.runtime: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

# runtime + test extras (pytest, pin, example-robot-data, scipy)
$(VENV)/.test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@ $(VENV)/.runtime

install: $(VENV)/.runtime

test: $(VENV)/.test
	$(BIN)/python -m pytest -q

clean:
	rm -rf $(VENV) build *.egg-info

# benchmark: runtime + test + bench extras (matplotlib, Eigen and URDF headers for the Pinocchio C++ harness);
# writes benchmarks/REPORT.md, benchmarks/*.json and the plots (see benchmarks/run.py for the settings)
$(VENV)/.bench: pyproject.toml $(VENV)/.test
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	touch $@

.PHONY: bench
bench: $(VENV)/.bench
	$(BIN)/python -m benchmarks.run
