# Two commands on a fresh machine: `make demo` and `make test`. Both set everything up first.
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = "0" ] || echo sudo)
export PYOPENGL_PLATFORM ?= osmesa

.PHONY: setup demo test test-fast fuzz golden bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml
	@dpkg -s libosmesa6 >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq libosmesa6; }
	@# Debian's chromium: the batch gallery test opens index.html in it (Playwright drives the system browser)
	@command -v chromium >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq chromium; }
	@[ -x $(PY) ] || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	# the CPU wheel on disk; pyproject.toml only asks for a range so other environments can install
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e '.[dev,ray]'
	@touch $@

demo: setup
	$(PY) scripts/demo.py --out out

test: setup
	$(VENV)/bin/lint-imports
	$(PY) -m pytest -q

test-fast: setup
	$(VENV)/bin/lint-imports
	$(PY) -m pytest -q -m "not slow"

# every reader fuzzed with 10,000 derandomised hypothesis examples (make test runs 200 of them)
fuzz: setup
	$(PY) -m pytest -q --hypothesis-profile=fuzz tests/test_fuzz_readers.py

golden: setup
	$(PY) -m pytest -q --update-golden tests/test_golden.py

# render speed and memory (~3 min), then batch throughput side by side (~8 min, an otherwise idle machine)
bench: setup
	$(PY) scripts/bench_render.py --json out/bench_render.json
	$(PY) scripts/bench_batch.py --json out/bench_batch.json

clean:
	rm -rf out test_output .pytest_cache
