# Two commands on a fresh machine:  `make run`  (set up + default experiment)  and  `make test`  (set up + tests).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
# The CPU build of torch. On the project's machines `torch==2.13.0` resolves to a local CPU wheel; elsewhere pass
# your platform's CPU build, e.g. `make test TORCH="torch --index-url <PyTorch's CPU wheel index>"`.
TORCH  ?= torch==2.13.0
# Test workers (pytest-xdist): one per core of the 2-core CI machine; `make test WORKERS=auto` takes every core.
WORKERS ?= 2

.PHONY: setup run test lint clean

setup: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -c "import torch" 2>/dev/null || $(BIN)/python -m pip install --quiet $(TORCH)
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

run: setup
	$(BIN)/python -m runners.train $(ARGS)

test: setup
	$(BIN)/python -m pytest -q -n $(WORKERS) --durations=15

lint: setup
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) *.egg-info
