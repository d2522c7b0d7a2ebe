# atlas — make targets. `make help` lists them. `make run` and `make test` set up .venv themselves.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CONFIG ?= configs/default.yaml
# The output file named inside a config (its `output:` key), so outputs are targets of configs.
output_of = $(shell sed -n 's/^output:[[:space:]]*//p' $(1) | tr -d "\"'")

.DEFAULT_GOAL := help
.PHONY: help run test test-fast atlas figures bench faults lint clean venv

help: ## list the targets
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | sed -e 's/:.*## /\t/' | expand -t 10

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

venv: $(STAMP) ## create .venv and install atlas with its dev tools

# The atlas file is a target of its config: recomputed only when the config (or the
# installed package) changed. A config without `output:` writes atlas's default path.
OUT := $(or $(call output_of,$(CONFIG)),outputs/default.h5)

$(OUT): $(CONFIG) $(STAMP)
	$(BIN)/atlas run $(CONFIG) -o $@
	$(BIN)/atlas plot $@

run: $(OUT) ## compute configs/default.yaml → outputs/default.h5 and outputs/default.png

atlas: $(OUT) ## compute any config: make atlas CONFIG=configs/x.yaml

# pytest-xdist: one worker per core (TEST_WORKERS=0: all in this process), each worker taking
# whole test files so that a module's fixtures are built once. On the 2-core machine, otherwise
# idle, the whole suite takes about 5 min 30 s in one process and 3 min 20 s in two.
TEST_WORKERS ?= auto

test: $(STAMP) ## check the import rules, then run the whole test suite (TEST_WORKERS=0: one process)
	$(BIN)/lint-imports --no-cache
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile

test-fast: $(STAMP) ## the fast subset: every test not marked slow (under a minute)
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile -m "not slow"

figures: $(STAMP) ## the essay's Figures 1-12 → outputs/figures/
	$(BIN)/atlas figures

bench: $(STAMP) ## benchmark table → outputs/bench.json
	$(BIN)/atlas bench

faults: $(STAMP) ## soak: kill -9, SIGTERM, disk full, lock races, Dask faults; prints one table
	$(BIN)/python -m tools.faults

lint: $(STAMP) ## ruff
	$(BIN)/ruff check atlas tests tools

clean: ## remove generated outputs and caches (keeps .venv)
	find outputs -mindepth 1 ! -name .gitkeep -exec rm -rf {} +
	find . -name __pycache__ -not -path './$(VENV)/*' -exec rm -rf {} +
	rm -rf .pytest_cache .ruff_cache .hypothesis
