# Two commands on a fresh machine with python3 (3.11+) and make: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench lint clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,bench]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(VENV)/bin/hdrjax tonemap data/cornell_box.exr -o out/cornell_box.png --method reinhard2002 --verbose

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	$(PY) benchmarks/bench_reinhard.py
	$(PY) benchmarks/bench_rgbe_read.py
	$(PY) benchmarks/bench_filters.py
	$(PY) benchmarks/bench_lights.py
	$(PY) benchmarks/bench_vision.py

lint: $(STAMP)
	$(VENV)/bin/ruff check hdrjax tests benchmarks

clean:
	rm -rf $(VENV) out .pytest_cache
