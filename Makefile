# aggsym: everything the project needs is installed here, into .venv, from pyproject.toml.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
MODELS := $(wildcard models/*.yaml)
SUDO   := $(shell [ "$$(id -u)" = 0 ] || command -v sudo)

.PHONY: install demo test tex generate clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# the package's bytecode, written once: an editable install compiles nothing, and where PYTHONDONTWRITEBYTECODE is set
# every `aggsym` command would compile its ~50 modules again (70 ms of Talos' 1.5 s); a module edited since is
# compiled afresh in memory, as Python does for any stale .pyc
BYTECODE := $(BIN)/python -m compileall -q aggsym

# runtime only (sympy, numpy, jinja2, pyyaml)
$(VENV)/.runtime: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	$(BYTECODE)
	touch $@

# runtime + test extras (pytest, pin, example-robot-data, scipy, setuptools)
$(VENV)/.test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test]'
	$(BYTECODE)
	touch $@ $(VENV)/.runtime

install: $(VENV)/.runtime

# the main job on a bundled model: generate C, NumPy, LaTeX and the manifest, then compile and check the C
demo: $(VENV)/.runtime
	$(BIN)/aggsym generate models/double_pendulum.yaml -o build/demo/double_pendulum
	$(BIN)/aggsym check models/double_pendulum.yaml

# pdflatex, for the tests that compile the generated .tex (Debian's texlive-latex-base)
tex:
	@command -v pdflatex >/dev/null 2>&1 || { \
	  echo "installing pdflatex (Debian package texlive-latex-base) for the LaTeX tests"; \
	  $(SUDO) apt-get update -qq && \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends texlive-latex-base \
	    > /dev/null; }

# the suite on one process per core, at most 4 (each holds its own SymPy programs; a test file stays on one
# process, so its module fixtures are built once)
JOBS ?= $(shell n=$$(nproc 2>/dev/null || echo 1); [ $$n -gt 4 ] && n=4; echo $$n)

test: $(VENV)/.test tex
	$(BIN)/python -m pytest -q -n $(JOBS) --dist loadfile

# the committed outputs of every model in models/ (reproducible: make generate && git diff --exit-code generated/)
generate: $(VENV)/.runtime
	rm -rf generated
	for m in $(MODELS); do $(BIN)/aggsym generate $$m -q > /dev/null || exit 1; done

clean:
	rm -rf $(VENV) $(BATCH_VENV) build *.egg-info

# benchmark: runtime + test + bench extras (matplotlib, Eigen and URDF headers for the Pinocchio C++ harness);
# writes benchmarks/REPORT.md, benchmarks/*.json and the plots (see benchmarks/run.py for the settings)
$(VENV)/.bench: pyproject.toml $(VENV)/.test
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	touch $@

# the batched benchmark's own venv (benchmarks/batch/, section batch of benchmarks.run): its peers pin an older
# jax (adam-robotics 0.5 requires jax <= 0.6.0) than the project's, and torch is the CPU wheel 2.13.0
BATCH_VENV := .venv-batch
$(BATCH_VENV)/.ready: benchmarks/batch/requirements.txt pyproject.toml
	$(PYTHON) -m venv $(BATCH_VENV)
	$(BATCH_VENV)/bin/python -m pip install --quiet -r benchmarks/batch/requirements.txt -e .
	touch $@

.PHONY: bench
bench: $(VENV)/.bench $(BATCH_VENV)/.ready
	$(BYTECODE)
	$(BIN)/python -m benchmarks.run
