# motiondiff: `make train` and `make test` set everything up on a fresh machine (see README).
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
SHARED ?= ../shared
BANDAI := $(SHARED)/data/bandai-namco
# Tool caches stay inside the project, never in the user's home.
export WANDB_MODE ?= offline
export MPLCONFIGDIR := $(CURDIR)/.cache/matplotlib
export HF_HOME := $(CURDIR)/.cache/huggingface
export HF_HUB_OFFLINE := 1
export TRANSFORMERS_OFFLINE := 1

.PHONY: setup train test lint format data lock clean

setup: $(VENV)/.installed

# Reinstall when the dependencies change. torch==2.13.0 is the CPU build (a wheel on this machine's disk).
$(VENV)/.installed: pyproject.toml requirements.lock
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet --progress-bar off -c requirements.lock -e '.[dev]'
	@touch $@

train: setup
	$(PY) -m motiondiff.cli.quickstart

test: setup
	$(PY) -m pytest -q

lint: setup
	$(VENV)/bin/ruff check src tests
	$(VENV)/bin/ruff format --check src tests

format: setup
	$(VENV)/bin/ruff format src tests
	$(VENV)/bin/ruff check --fix src tests

# Rebuild the embedded dataset from the Bandai Namco zips (every content x style, one clip each, <= 6 s).
data: setup
	$(PY) -m motiondiff.data.prepare bandai --src $(BANDAI)/bandai-ds1.zip --src $(BANDAI)/bandai-ds2.zip \
		--out data/bandai_mini --per-group 1 --max-frames 120 --compact --seed 0 --force

lock: setup
	( echo "# Exact versions of every installed package (pip freeze of a working .venv); used as pip constraints by the Makefile."; \
	  echo "# Regenerate after changing dependencies in pyproject.toml: make lock"; \
	  $(PY) -m pip freeze --exclude-editable | sed 's/^torch==\(.*\)+cpu/torch==\1/' ) > requirements.lock

clean:
	rm -rf $(VENV) .cache .pytest_cache .ruff_cache
