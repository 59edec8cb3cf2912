# Two commands on a fresh machine: `make demo` and `make test`. Both set everything up first: `setup` what the
# demo needs (OSMesa, the venv), `setup-test` that plus the browser the batch gallery test opens.
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test
SUDO   := $(shell [ "$$(id -u)" = "0" ] || echo sudo)
export PYOPENGL_PLATFORM ?= osmesa

.PHONY: setup setup-test demo test test-fast fuzz golden bench clean

setup: $(STAMP)

setup-test: $(TEST_STAMP)

$(STAMP): pyproject.toml
	@dpkg -s libosmesa6 >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq libosmesa6; }
	@[ -x $(PY) ] || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	# the CPU wheel on disk; pyproject.toml only asks for a range so other environments can install
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e '.[dev,ray]'
	@touch $@

# Debian's chromium, for the tests only: the batch gallery test opens index.html in it (Playwright drives the
# system browser)
$(TEST_STAMP): $(STAMP)
	@command -v chromium >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq chromium; }
	@touch $@

demo: setup
	$(PY) scripts/demo.py --out out

test: setup-test
	$(VENV)/bin/lint-imports
	$(PY) -m pytest -q

test-fast: setup-test
	$(VENV)/bin/lint-imports
	$(PY) -m pytest -q -m "not slow"

# every reader fuzzed with 10,000 derandomised hypothesis examples (make test runs 200 of them)
fuzz: setup
	$(PY) -m pytest -q --hypothesis-profile=fuzz tests/test_fuzz_readers.py

golden: setup
	$(PY) -m pytest -q --update-golden tests/test_golden.py

# render speed and memory (~3 min), then batch throughput side by side (~8 min, an otherwise idle machine)
bench: setup
	$(PY) scripts/bench.py render --json out/bench_render.json
	$(PY) scripts/bench.py batch --json out/bench_batch.json

clean:
	rm -rf out test_output .pytest_cache
