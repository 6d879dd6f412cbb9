# formation-ftc: every target creates .venv itself on a fresh machine (Python >= 3.11 and pip).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: install demo test test-fast lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

## main job: reproduce all five papers into out/reproduction (index.html + summary.json)
demo: $(STAMP)
	$(BIN)/formation-ftc reproduce all --out out/reproduction --force

## whole test suite (2 xdist workers)
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q --durations=15

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -x -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks

bench: $(STAMP)
	$(BIN)/python benchmarks/engine.py
	$(BIN)/python benchmarks/li2020.py
	$(BIN)/python benchmarks/gui2022.py
	$(BIN)/python benchmarks/campaign.py

clean:
	rm -rf $(VENV) out .pytest_cache
