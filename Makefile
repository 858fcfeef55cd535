# Every target sets itself up: a fresh clone needs only `make run` or `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# Two installs: the service alone (`make run`), and the service with the test and figure
# tools, the `dev` and `figures` extras (every other target).
SERVICE_STAMP := $(VENV)/.service-stamp
STAMP         := $(VENV)/.installed-stamp
# pip names every package it fetches; tools/heartbeat.py says what is still running when
# it is silent (venv's ensurepip, building asterix-decoder's C extension, unpacking numpy).
PIP_INSTALL := $(PYTHON) tools/heartbeat.py $(BIN)/python -m pip install --progress-bar off

.PHONY: run test test-prerequisites lint bench soak openapi figures clean

$(BIN)/python:
	@echo "==> creating the virtual environment $(VENV)/ ($(PYTHON))"
	@$(PYTHON) tools/heartbeat.py $(PYTHON) -m venv $(VENV)
	@echo "==> upgrading pip in $(VENV)/"
	@$(PIP_INSTALL) --quiet --upgrade pip

$(SERVICE_STAMP): pyproject.toml | $(BIN)/python
	@echo "==> installing credal-fusion and the service's dependencies only (first time: a minute or more, asterix-decoder is compiled)"
	@$(PIP_INSTALL) -e .
	@touch $@
	@echo "==> $(VENV)/ is ready to run the service"

$(STAMP): pyproject.toml | $(BIN)/python
	@echo "==> installing credal-fusion with its test and figure tools, the dev and figures extras (first time: 2 minutes or more)"
	@$(PIP_INSTALL) -e '.[dev,figures]'
	@touch $@ $(SERVICE_STAMP)
	@echo "==> $(VENV)/ is ready"

run: $(SERVICE_STAMP)
	@mkdir -p data
	@echo "==> starting the service (sqlite store in data/); Ctrl-C stops it"
	$(BIN)/credal-fusion serve --host 127.0.0.1 --port 8000

# Debian's chromium and redis-server, installed when missing (tools/test-prerequisites);
# the tests' Redis: the one at CREDAL_TEST_REDIS_URL (default 127.0.0.1:6379), else a
# private redis-server for the run (tools/with-test-redis).
test-prerequisites:
	@tools/test-prerequisites

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: test-prerequisites lint
	tools/with-test-redis $(BIN)/python $(BIN)/python -m pytest -q -n auto

openapi: $(STAMP)
	$(BIN)/python -m app.openapi openapi.json
	$(BIN)/python -m app.asyncapi docs/asyncapi.yaml

# Every figure of docs/RESULTS.md and its numbers (docs/figures/NAME.png, NAME.txt); one BLAS
# thread, as bench/peers.py times its trackers (the peers figure reruns that bench).
figures: $(STAMP)
	MPLBACKEND=Agg OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \
		$(BIN)/python -m evaluation.figures --out docs/figures

bench: $(STAMP)
	@for b in $(filter-out bench/soak.py,$(wildcard bench/*.py)); do echo "== $$b"; $(BIN)/python $$b || exit 1; done

# A few minutes per store of steady load on a live server: RSS and store size must stay flat;
# then the honest load alone and beside an anonymous attacker, in alternating pairs of phases:
# its p99 ratio not significantly above 1.10 (95 % interval bootstrapped over the pairs;
# "inconclusive" when it holds 1.10), its error rate not significantly higher (one-sided
# Fisher exact test; the increase's 95 % bound printed).
soak: $(STAMP)
	$(BIN)/python bench/soak.py
	$(BIN)/python bench/soak.py --crowd

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache .hypothesis
