# Two commands on a fresh machine: `make demo` and `make test`. Both set everything up first: `setup` what the
# demo needs (OSMesa, the venv), `setup-test` that plus the browser the batch gallery test opens. `make check`
# is the edit loop: the import contracts and the fast tests.
SHELL  := /bin/bash
.SHELLFLAGS := -o pipefail -c
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
TORCH  := 2.13.0
TEST_STAMP := $(VENV)/.installed-test
SUDO   := $(shell [ "$$(id -u)" = "0" ] || echo sudo)
export PYOPENGL_PLATFORM ?= osmesa
# test workers: two processes share the machine's cores (tests are xdist-safe: tmp_path outputs, atomic caches);
# a file's tests stay on one worker, so its module fixtures (trained models, renders) are built once; files go out
# in collection order, the longest first (tests/conftest.py LONGEST_FIRST)
WORKERS ?= 2
XDIST  = -n $(WORKERS) --dist loadfile --no-loadscope-reorder
# pip quiet: no progress, no version check, and not the warnings a machine's pip configuration can add about index
# folders it does not have ("Location ... is ignored"); pip's errors and its exit status still come through
PIP_INSTALL = $(PY) -m pip install -q --disable-pip-version-check
QUIET_PIP = 2>&1 | { grep -v "^WARNING: Location '.*' is ignored" || true; }

.PHONY: setup setup-test demo test check fuzz golden bench clean

# the test workers fill the cores already: OSMesa's llvmpipe rasterises in the rendering thread instead of starting
# threads of its own (7-9% less CPU per mesh render measured here, the same wall time)
test check: export LP_NUM_THREADS = 0

setup: $(STAMP)

setup-test: $(TEST_STAMP)

$(STAMP): pyproject.toml
	@dpkg -s libosmesa6 >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq libosmesa6; }
	@[ -x $(PY) ] || python3 -m venv $(VENV)
	@echo "installing the Python packages into $(VENV) (a minute or two the first time) ..."
	@$(PIP_INSTALL) --upgrade pip $(QUIET_PIP)
	@# the CPU wheel on disk, by pip, which knows where it lies; pyproject.toml only asks for a range so other
	@# environments can install
	@$(PIP_INSTALL) torch==$(TORCH) uv $(QUIET_PIP)
	@# everything else by uv: it downloads and unpacks in parallel (about 18 s here, pip 56 s); the constraint
	@# keeps the torch just installed, and the bytecode is compiled as pip would
	@echo "torch==$(TORCH)" > $(VENV)/constraints.txt
	@$(VENV)/bin/uv pip install -q --python $(PY) --compile-bytecode --constraint $(VENV)/constraints.txt \
		-e '.[dev,ray,app]'
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
	$(PY) -m pytest -q $(XDIST) --durations=15

# the edit loop (a few minutes): import contracts and every test not marked slow
check: setup-test
	$(VENV)/bin/lint-imports
	$(PY) -m pytest -q $(XDIST) -m "not slow" --hypothesis-profile=check

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
