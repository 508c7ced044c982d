# One-command set-up on a fresh machine: `make demo` runs the main job, `make test` the test suite.
# Both create the virtual environment .venv and install snoworm into it first.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
OUT ?= out

.PHONY: demo test lint test-x86-64-v2 differential bench paper docs clean

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

# lint, format check and type check (rules in pyproject.toml [tool.ruff] and [tool.mypy]: the
# public modules); .ci/run runs it after the tests
lint: $(VENV)/.installed
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/mypy

# The reference tests again on a second numeric path: an x86-64-v2 CPU emulated (OpenBLAS's
# Nehalem kernels, NumPy without AVX2/AVX-512 loops), which differs from the native path on any
# AVX2 or AVX-512 machine, so a test that depends on the CPU fails here first (.ci/run runs it).
X86_64_V2 := OPENBLAS_CORETYPE=Nehalem NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR"
test-x86-64-v2: $(VENV)/.installed
	$(X86_64_V2) $(PY) -m pytest -q -p no:cacheprovider tests/test_reference_summaries.py tests/test_tight_reference.py

# The differential tests at length: 60 hypothesis sequences of scenarios in one process against
# each run alone in a fresh process (make test runs 4; tests/test_differential.py)
differential: $(VENV)/.installed
	SNOWORM_DIFF_EXAMPLES=60 $(PY) -m pytest -q -p no:cacheprovider tests/test_differential.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis .mypy_cache
