# The two entry points of the README: `make study` (the full study) and `make test` (the checks).
# Both create .venv with python3 and install emdm with every extra the checks need.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
OUT    ?= results
ARGS   ?=

.PHONY: install study test lint typecheck unit fuzz clean

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,all]'
	touch $@

study: $(STAMP)
	$(BIN)/emdm report --out $(OUT)/report $(ARGS)

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks

typecheck: $(STAMP)
	$(BIN)/mypy

unit: $(STAMP)
	$(BIN)/python -c "import emdm; emdm.precompile()"   # once, so the workers only load them
	$(BIN)/pytest -n 2   # both cores (pytest-xdist)

test: lint typecheck unit

fuzz: $(STAMP)   # the long profiles: 10,000 cases per fuzz test, signals at 200 random moments of run, 20 of each command with workers
	EMDM_FUZZ_EXAMPLES=$${EMDM_FUZZ_EXAMPLES:-10000} $(BIN)/pytest -n 2 tests/test_fuzz.py
	EMDM_SIGNAL_MOMENTS=$${EMDM_SIGNAL_MOMENTS:-200} EMDM_PARALLEL_MOMENTS=$${EMDM_PARALLEL_MOMENTS:-20} $(BIN)/pytest tests/test_signals.py -k random_moment

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .mypy_cache .ruff_cache
