# Every target sets itself up: a fresh clone needs only `make run` or `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp

.PHONY: run test lint bench soak openapi figures clean

# Each step says what it does, and pip names every package it installs (the
# first run takes about two minutes).
$(STAMP): pyproject.toml
	@test -x $(BIN)/python || { echo "==> creating the virtual environment $(VENV)/ ($(PYTHON))"; $(PYTHON) -m venv $(VENV); }
	@echo "==> upgrading pip in $(VENV)/"
	@$(BIN)/python -m pip install --quiet --upgrade pip
	@echo "==> installing credal-fusion and its dependencies from pyproject.toml (first time: about 2 minutes)"
	@$(BIN)/python -m pip install --progress-bar off -e '.[dev,figures]'
	@touch $(STAMP)
	@echo "==> $(VENV)/ is ready"

run: $(STAMP)
	@mkdir -p data
	@echo "==> starting the service (sqlite store in data/); Ctrl-C stops it"
	$(BIN)/credal-fusion serve --host 127.0.0.1 --port 8000

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: lint
	$(BIN)/python -m pytest -q

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
# then the honest load beside an anonymous attacker: its p99 and error rate within 10 %.
soak: $(STAMP)
	$(BIN)/python bench/soak.py
	$(BIN)/python bench/soak.py --crowd

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache .hypothesis
