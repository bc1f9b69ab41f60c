# ssw: the two commands of the README are `make study` and `make test`.
# Both set up the environment first (scripts/setup.sh: idempotent, seconds when done).
# Paths are quoted where the shell sees them: a clone may live under a folder whose name has
# spaces or non-ASCII letters (`~/My Projects/ssw`); make's own functions split on spaces,
# so no path goes through them.
VENV    := .venv
PY      := "$(VENV)/bin/python"
# Snakemake's Slurm plugin asks `scontrol show config` when it is imported, at every start.
# With the local cluster of scripts/slurm-local.sh installed but stopped (after a reboot),
# scontrol retries the absent controller for the plugin's 10 s: these Snakemake calls then
# read an empty Slurm configuration instead, which scontrol refuses at once.
SLURM_ENV := $(shell bash scripts/slurm-local.sh down 2>/dev/null && echo SLURM_CONF=/dev/null)
SMK     := env $(SLURM_ENV) "$(VENV)/bin/snakemake"
CORES   ?= 2
CONFIG  ?= config/config.yaml
PYTEST_ARGS ?=
# pytest-xdist workers of `make test` (auto: one per core; 0: one process, no workers)
TEST_WORKERS ?= auto

.PHONY: setup study test test-long test-all lint bench report docs clean

setup:
	@bash scripts/setup.sh

## The default study (the thesis study in config/config.yaml), results under results/.
## (Snakemake finds workflow/Snakefile and its workstation profile workflow/profiles/default.)
## (ssw.warmstart: the jobs' warm process imports ssw while Snakemake itself starts.)
study: setup
	$(PY) -m ssw.warmstart -- $(SMK) --cores $(CORES) --configfile "$(CONFIG)"

## The test suite (default: everything but the `slow` marker) on every core (pytest-xdist:
## TEST_WORKERS=auto; tests/conftest.py keeps the tests that share a fixture or a machine-wide
## resource on one worker), lint and workflow checks.
test: setup
	@# The local Slurm of tests/test_slurm.py. Under CI=true a cluster that does not start
	@# fails the run; elsewhere its tests skip and say why.
	@if [ "$${CI:-}" = true ]; then bash scripts/slurm-local.sh start; \
	else bash scripts/slurm-local.sh start || echo "[test] local Slurm not started: its tests skip and say why (CI=true: they fail)"; fi
	"$(VENV)/bin/ruff" check ssw tests
	"$(VENV)/bin/snakefmt" --check workflow
	$(SMK) --lint --configfile "$(CONFIG)"
	PATH="$$(cd "$(VENV)/bin" && pwd):$$PATH" $(PY) -m pytest -m "not slow and not long" -n $(TEST_WORKERS) $(PYTEST_ARGS)

## The long checks the default run leaves out (whole studies on Slurm and in a browser, the
## cluster's waits on held and vanished jobs, the device design through Snakemake, limit
## loads, the misspecified device's calibration, the documentation site from nothing), each with a faster check of the same rule
## in the default run: a few minutes more; CI runs them after `make test`.
test-long: setup
	@if [ "$${CI:-}" = true ]; then bash scripts/slurm-local.sh start; \
	else bash scripts/slurm-local.sh start || echo "[test] local Slurm not started: its tests skip and say why (CI=true: they fail)"; fi
	PATH="$$(cd "$(VENV)/bin" && pwd):$$PATH" $(PY) -m pytest -m "long and not slow" -n $(TEST_WORKERS) $(PYTEST_ARGS)

## Everything, slow tests included.
test-all: setup
	PATH="$$(cd "$(VENV)/bin" && pwd):$$PATH" $(PY) -m pytest -n $(TEST_WORKERS) $(PYTEST_ARGS)

lint: setup
	"$(VENV)/bin/ruff" check ssw tests
	"$(VENV)/bin/snakefmt" --check workflow
	$(SMK) --lint --configfile "$(CONFIG)"

## Benchmarks (figures go into the README).
## (ssw bench dynamic, the elastodynamic FEM wall, takes several minutes more: run it alone.)
bench: setup
	"$(VENV)/bin/ssw" bench contact --engines --wall
	"$(VENV)/bin/ssw" bench layered
	"$(VENV)/bin/ssw" bench chain
	"$(VENV)/bin/ssw" bench tof
	"$(VENV)/bin/ssw" bench study
	"$(VENV)/bin/ssw" bench lu

## The study's report (Snakemake's own; after `make study`): results/report.html.
report: setup
	$(SMK) --cores $(CORES) --configfile "$(CONFIG)" --report results/report.html

## The documentation site (Sphinx + MyST; the configuration, command-line and API
## references are generated from the schemas, the parser and the docstrings):
## docs/_build/html/index.html. Warnings are errors, as in tests/test_docs.py.
## SPHINXOPTS adds options (tests/test_docs.py: a doctree cache and -a).
DOCS_OUT ?= docs/_build/html
SPHINXOPTS ?=
docs: setup
	"$(VENV)/bin/sphinx-build" -b html -W --keep-going -n -q $(SPHINXOPTS) docs "$(DOCS_OUT)"
	@echo "docs: $(DOCS_OUT)/index.html"

clean:
	rm -rf results .snakemake docs/_build
