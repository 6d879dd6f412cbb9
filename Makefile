# formation-ftc: every target creates .venv itself on a fresh machine (Python >= 3.11 and pip).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: install demo test test-fast lint typecheck bench bench-cli docs examples wheel-smoke schema-file clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install -q -e ".[test,docs]"
	touch $(DOCS_STAMP)

## main job: reproduce all five papers into out/reproduction (index.html + summary.json)
demo: $(STAMP)
	$(BIN)/formation-ftc reproduce all --out out/reproduction --force

## whole test suite (2 xdist workers)
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 --dist worksteal -q --durations=15

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -x -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples docs/hooks
	$(BIN)/ruff format --check src tests benchmarks examples docs/hooks
	$(BIN)/lint-imports

## static type check of src/ (configuration and its rationale: [tool.mypy] in pyproject.toml)
typecheck: $(STAMP)
	$(BIN)/mypy

## documentation site into site/ (strict: any warning fails; runs every example at reduced size)
docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

## every example at reduced size (as the docs build runs them)
examples: $(STAMP)
	set -e; for f in examples/[0-9][0-9]_*.py; do echo "== $$f"; MPLBACKEND=Agg $(BIN)/python $$f --quick; done

## wheel + sdist, installed into a fresh venv, list / run / campaign run from there
wheel-smoke: $(STAMP)
	.ci/wheel-smoke $(BIN)/python

## regenerate the composed schema shipped with the package (a test says when it is stale)
schema-file: $(STAMP)
	$(BIN)/python -m formation_ftc.shipped_schema

## command-line start-up times (--help, --version, list, show, schema) against 0.3 s
bench-cli: $(STAMP)
	$(BIN)/python benchmarks/cli.py

bench: $(STAMP)
	$(BIN)/python benchmarks/engine.py
	$(BIN)/python benchmarks/li2020.py
	$(BIN)/python benchmarks/gui2022.py
	$(BIN)/python benchmarks/campaign.py
	$(BIN)/python benchmarks/grid_batch.py
	$(BIN)/python benchmarks/metric_fold.py
	$(BIN)/python benchmarks/cli.py

clean:
	rm -rf $(VENV) out .pytest_cache site .cache/docs-examples
