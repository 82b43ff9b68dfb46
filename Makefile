# conesim: `make run` and `make test` each set up .venv on first use.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test lint typecheck bench train clean clean-cache

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# torch's CPU build goes in first, pinned: the rl extra (stable-baselines3)
# then finds a torch it accepts and pulls nothing more. Left to the extra alone,
# pip would take the newest torch, a CUDA build of several GB (README,
# "Training a policy").
TORCH := torch==2.13.0

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet '$(TORCH)'
	$(BIN)/python -m pip install --quiet -e '.[dev,render,ros,ray,rl]'
	touch $(STAMP)

# A headless closed-loop lap on the default track (trackdrive): rtk sensors,
# EKF localization, the seed's planner and pure pursuit. Prints the results and
# writes runs/latest/result.json and runs/latest/run.png.
run: $(STAMP)
	$(BIN)/conesim run --track trackdrive --laps 1 --out runs/latest

# The whole test suite, then lint and type check.
test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python scripts/typecheck.py

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

typecheck: $(STAMP)
	$(BIN)/python scripts/typecheck.py

# The training baseline: PPO on generated tracks for 26 minutes, tested on 20
# unseen ones; writes runs/ppo/ (README, "Training a policy").
train: $(STAMP)
	$(BIN)/python examples/train_ppo.py --minutes 26 --out runs/ppo

# Every benchmark script; their figures go to benchmarks/RESULTS.md.
bench: $(STAMP)
	$(BIN)/python benchmarks/write_results.py

# Remove numba's cached kernels (the next run compiles them afresh). Never
# needed after an edit: each kernel's cache is keyed by all the code it
# reaches (conesim/core/kernel_cache.py); this only frees the space.
clean-cache:
	find conesim sim localization planner envs tracks -name __pycache__ -type d -prune -exec rm -rf {} +

clean: clean-cache
	rm -rf $(VENV) build *.egg-info .pytest_cache .mypy_cache .ruff_cache
