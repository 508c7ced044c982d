# One-command set-up on a fresh machine: `make demo` runs the main job, `make test` the test suite.
# Both create the virtual environment .venv and install snoworm into it first.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
OUT ?= out

.PHONY: demo test bench paper docs clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $@

demo: $(VENV)/.installed
	$(VENV)/bin/snoworm run scenarios/inchworm6.yaml --out $(OUT)/inchworm6

paper: $(VENV)/.installed
	$(VENV)/bin/snoworm paper --out $(OUT)/paper

bench: $(VENV)/.installed
	$(PY) benchmarks/run.py --out $(OUT)/benchmarks.json

# API reference from the docstrings (pdoc), into out/docs; fails on any pdoc warning
docs: $(VENV)/.installed
	$(PY) docs/api.py $(OUT)/docs

test: $(VENV)/.installed
	$(PY) -m pytest -q

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis
