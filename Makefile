# Two commands on a fresh machine with python3 (3.11+) and make: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test docs bench bench-quick lint clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,bench,lint]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(VENV)/bin/hdrjax tonemap data/cornell_box.exr -o out/cornell_box.png --method reinhard2002 --verbose

# test files run in parallel, a file's tests in order on one worker (up to 4 workers)
TEST_WORKERS ?= $(shell $(PYTHON) -c "import os; print(min(4, os.cpu_count() or 1))")

test: $(STAMP)
	$(PY) -m pytest -n $(TEST_WORKERS) --dist loadfile --durations=15

# the documentation site (MkDocs Material, API pages from the docstrings) into site/;
# --strict: a broken link or a docstring the reference cannot render is an error
DOCS_STAMP := $(VENV)/.docs-installed

$(DOCS_STAMP): pyproject.toml $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

# the full suite writes benchmarks/results/ and regenerates the tables of docs/performance.md
bench: $(STAMP)
	$(PY) benchmarks/run.py
	$(PY) benchmarks/report.py --readme docs/performance.md

# a few minutes: small sizes, its own folder (the committed full results stay as they are)
bench-quick: $(STAMP)
	$(PY) benchmarks/run.py --quick --out benchmarks/results/quick

# ruff, then mypy on the package (it ships py.typed; configured in pyproject.toml)
lint: $(STAMP)
	$(VENV)/bin/ruff check hdrjax tests benchmarks
	$(VENV)/bin/mypy

clean:
	rm -rf $(VENV) out .pytest_cache site .mypy_cache
