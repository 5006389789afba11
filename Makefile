# Two commands on a fresh machine with python3 (3.11+) and make: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench bench-quick lint clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,bench]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(VENV)/bin/hdrjax tonemap data/cornell_box.exr -o out/cornell_box.png --method reinhard2002 --verbose

# test files run in parallel, a file's tests in order on one worker (up to 4 workers)
TEST_WORKERS ?= $(shell $(PYTHON) -c "import os; print(min(4, os.cpu_count() or 1))")

test: $(STAMP)
	$(PY) -m pytest -n $(TEST_WORKERS) --dist loadfile --durations=15

# the full suite writes benchmarks/results/ and regenerates the README's performance section
bench: $(STAMP)
	$(PY) benchmarks/run.py
	$(PY) benchmarks/report.py --readme README.md

# a few minutes: small sizes, its own folder (the committed full results stay as they are)
bench-quick: $(STAMP)
	$(PY) benchmarks/run.py --quick --out benchmarks/results/quick

lint: $(STAMP)
	$(VENV)/bin/ruff check hdrjax tests benchmarks

clean:
	rm -rf $(VENV) out .pytest_cache
