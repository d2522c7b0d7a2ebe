# atlas — make targets. `make help` lists them. `make run` and `make test` set up .venv themselves.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# Two stamps: RUN, atlas and its runtime dependencies (`make run`, what a user of atlas needs);
# DEV, those and the dev extras (`make test`, lint, docs, notebook, faults: pytest, ruff, mkdocs,
# Playwright, Jupyter, Dask). DEV implies RUN, so either order installs each thing once.
RUN := $(VENV)/.installed-run
DEV := $(VENV)/.installed
CONFIG ?= configs/default.yaml
# The output file named inside a config (its `output:` key), so outputs are targets of configs.
output_of = $(shell sed -n 's/^output:[[:space:]]*//p' $(1) | tr -d "\"'")

.DEFAULT_GOAL := help
.PHONY: stability driven-sweep help run test test-fast atlas figures bench bench-peers faults lint clean venv docs

help: ## list the targets
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | sed -e 's/:.*## /\t/' | expand -t 10

# .venv made if missing, pip upgraded, pendulum-atlas's old distribution name removed if there.
VENV_READY := { test -x $(BIN)/python || $(PYTHON) -m venv $(VENV); } \
	&& $(BIN)/python -m pip install --quiet --upgrade pip \
	&& { ! $(BIN)/python -m pip show --quiet atlas >/dev/null 2>&1 \
	     || $(BIN)/python -m pip uninstall --quiet --yes atlas; }

# Up to date after a dev install: nothing installed, and nothing downstream recomputed.
$(RUN): pyproject.toml
	[ $(DEV) -nt pyproject.toml ] || { $(VENV_READY) && $(BIN)/python -m pip install --quiet -e .; }
	touch $@

$(DEV): pyproject.toml
	$(VENV_READY)
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@
	[ $(RUN) -nt pyproject.toml ] || touch $(RUN)

venv: $(DEV) ## create .venv and install atlas with its dev tools (make run installs the runtime only)

# The atlas file is a target of its config: recomputed only when the config (or the
# installed package) changed. A config without `output:` writes atlas's default path. Its
# figures are a target of the file: drawn when missing or older than the file, also after an
# `atlas run` of the same config made the file itself up to date. (`atlas plot` writes
# NAME.png, the basin map, with the others: it stands for all of them.)
OUT := $(or $(call output_of,$(CONFIG)),outputs/default.h5)
FIGURE := $(basename $(OUT)).png

$(OUT): $(CONFIG) $(RUN)
	$(BIN)/atlas run $(CONFIG) -o $@

$(FIGURE): $(OUT)
	$(BIN)/atlas plot $<

run: $(FIGURE) ## compute configs/default.yaml → outputs/default.h5 and outputs/default.png

atlas: $(FIGURE) ## compute any config and draw its figures: make atlas CONFIG=configs/x.yaml

# pytest-xdist: one worker per core (TEST_WORKERS=0: all in this process), each worker taking
# whole test files so that a module's fixtures are built once. On the 2-core machine the whole
# suite takes 10–12 min in two processes on a fresh clone, 7 once compiled (docs/contributing.md).
TEST_WORKERS ?= auto

test: $(DEV) ## import rules, the docs (--strict), then the whole test suite (TEST_WORKERS=0: one process)
	$(BIN)/lint-imports --no-cache
	$(MKDOCS) build --strict --quiet
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile

test-fast: $(DEV) ## the fast subset: every test not marked slow (about 2 min)
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile -m "not slow"

stability: $(RUN) ## Menck's figure, exact: configs/swing_stability.yaml (1,001 torques) → outputs/swing_stability*.png
	$(BIN)/atlas stability configs/swing_stability.yaml -v
	$(BIN)/atlas plot outputs/swing_stability.h5

driven-sweep: $(RUN) ## the driven pendulum's attractors followed over A in [1, 2] (101 points, 10^4 samples each) → outputs/driven_sweep*.png
	$(BIN)/atlas stability configs/driven_sweep.yaml -v
	$(BIN)/atlas plot outputs/driven_sweep.h5

figures: $(RUN) ## the essay's Figures 1-12 → outputs/figures/
	$(BIN)/atlas figures

bench: $(RUN) ## benchmark table → outputs/bench.json
	$(BIN)/atlas bench

# The published Python peer, side by side on the same points and machine: pynamicalsys in its
# own venv (.venv-peers, no dependency of atlas), atlas from .venv (docs/peers.md).
PEERS := .venv-peers

$(PEERS)/bin/python:
	$(PYTHON) -m venv $(PEERS)
	$(PEERS)/bin/python -m pip install --quiet --upgrade pip pynamicalsys

bench-peers: $(RUN) $(PEERS)/bin/python ## pynamicalsys against atlas on the driven pendulum's 128² points → outputs/peer_driven.json
	$(BIN)/python -m tools.peer_driven --peer-python $(PEERS)/bin/python --out outputs/peer_driven.json

faults: $(DEV) ## soak: kill -9, SIGTERM, disk full, lock races, Dask faults; prints one table
	$(BIN)/python -m tools.faults

# The documentation site (mkdocs.yml → site/). --strict: a broken link, anchor or API reference
# (mkdocstrings reads the docstrings from the sources) fails the build.
MKDOCS := NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs

docs: $(DEV) ## the documentation site → site/index.html (mkdocs build --strict)
	$(MKDOCS) build --strict

# docs/tutorial.ipynb is stored with its outputs (a code host shows its figures): this runs it
# in a fresh kernel and stores them, stamped with the hash of its code (the tests check it).
.PHONY: notebook
notebook: $(DEV) ## run docs/tutorial.ipynb and store it with its outputs (figures, printouts)
	$(BIN)/python tests/commands/test_tutorial.py

lint: $(DEV) ## ruff
	$(BIN)/ruff check atlas tests tools

clean: ## remove generated outputs and caches (keeps .venv)
	find outputs -mindepth 1 ! -name .gitkeep -exec rm -rf {} +
	find . -name __pycache__ -not -path './$(VENV)/*' -exec rm -rf {} +
	rm -rf .pytest_cache .ruff_cache .hypothesis
