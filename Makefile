# make run: set up (first time) and run the main job; make test: set up and run every test (what CI runs);
# make check: lint and the fast lane (the tests not marked slow), for use while editing.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test check lint typecheck bench fuzz clean docs docs-serve browser

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	# the MJCF arms of the tests (Panda, Sawyer, iiwa, Jaco, Kinova Gen3, UR5e, xArm7 ...): files only, read by
	# MuJoCo and never imported, so without the packages' own dependencies
	$(BIN)/python -m pip install --quiet --no-deps "robosuite==1.5.2" "robosuite-models==1.0.0"
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/armdyn demo

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples
	$(BIN)/ruff format --check src tests benchmarks examples
	$(BIN)/mypy src/armdyn

typecheck: $(STAMP)
	$(BIN)/mypy src/armdyn

# headless Chromium for the viewer's browser tests: Debian's package, installed when missing if we are root;
# otherwise (or offline) those tests skip, saying why
browser:
	@command -v chromium >/dev/null || command -v chromium-browser >/dev/null || command -v google-chrome >/dev/null || \
	  { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null && apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; } || \
	  echo "no Chromium (and not installed: needs root and apt-get): the browser tests will skip"

# two workers, each test file in one (the files' own fixtures then run once)
test: lint browser
	$(BIN)/python -m pytest -q -n 2 --dist loadfile

# the fast lane: every module's tests but those marked slow (under a minute once Numba's cache is warm)
check: lint
	$(BIN)/python -m pytest -q -n 2 --dist loadfile -m "not slow"

fuzz: $(STAMP)
	ARMDYN_FUZZ_REPORT=fuzz-report.txt $(BIN)/python -m pytest -q tests/test_fuzz.py

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[bench]"
	$(BIN)/python benchmarks/bench_dynamics.py
	$(BIN)/python benchmarks/bench_task.py
	$(BIN)/python benchmarks/bench_derivatives.py
	$(BIN)/python benchmarks/bench_codegen.py
	$(BIN)/python benchmarks/bench_targets.py
	$(BIN)/python benchmarks/bench_casadi.py
	$(BIN)/python benchmarks/bench_identification.py
	$(BIN)/python benchmarks/bench_identification_speed.py
	$(BIN)/python benchmarks/bench_observer.py

clean:
	rm -rf $(VENV) build site src/*.egg-info .pytest_cache .ruff_cache "$${XDG_CACHE_HOME:-$$HOME/.cache}/armdyn"
	find src tests benchmarks examples -name __pycache__ -prune -exec rm -rf {} +

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# the site at http://127.0.0.1:8000, rebuilt on every edit of docs/ or src/
docs-serve: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs serve
