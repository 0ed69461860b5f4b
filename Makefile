# The two entry points of the README: `make study` (the full study) and `make test` (the checks).
# Both create .venv with python3 and install emdm with every extra the checks need.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
OUT    ?= results

.PHONY: install study test lint typecheck unit clean

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,lab,solvers,video]'
	touch $@

study: $(STAMP)
	$(BIN)/emdm run task1 --out $(OUT)/task1
	$(BIN)/emdm run task2 --out $(OUT)/task2
	$(BIN)/emdm solvers task2 --controller C-EMDM --out $(OUT)/task2-solvers
	$(BIN)/emdm solvers task1 --controller C-EMDM --solvers active-set,interior-point,admm,daqp,quadprog,slsqp --out $(OUT)/task1-solvers
	$(BIN)/emdm plot $(OUT)/task1 --out $(OUT)/task1/figures
	$(BIN)/emdm plot $(OUT)/task2 --out $(OUT)/task2/figures
	$(BIN)/emdm animate $(OUT)/task1 --out $(OUT)/task1/animations
	$(BIN)/emdm animate $(OUT)/task2 --out $(OUT)/task2/animations
	$(BIN)/emdm pareto task1 --controller UC-EMDM --out $(OUT)/task1-pareto-UC-EMDM
	$(BIN)/emdm pareto task1 --controller C-EMDM --out $(OUT)/task1-pareto-C-EMDM

lint: $(STAMP)
	$(BIN)/ruff check src tests
	$(BIN)/ruff format --check src tests

typecheck: $(STAMP)
	$(BIN)/mypy

unit: $(STAMP)
	$(BIN)/pytest

test: lint typecheck unit

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .mypy_cache .ruff_cache
