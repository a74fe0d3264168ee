# The two commands: `make book` (build the whole study) and `make test`.
# Both create the virtual environment on first use; everything else lives in the `study` package.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
PRESET ?= paper
SCHEDULER ?=
DEVICE ?= cpu
BOOK_ARGS ?=
export MUJOCO_GL ?= egl
export PYTHONHASHSEED := 0

.PHONY: book test test-book bench bench-recipe install clean

$(BIN)/.installed: requirements.txt pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.txt
	$(BIN)/python -m pip install --quiet --no-deps --no-build-isolation -e .
	touch $@

install: $(BIN)/.installed

## Execute every chapter with papermill (PRESET=paper by default) and build the HTML book in _build/html;
## SCHEDULER=local (or a Dask scheduler's address) trains the chapters' runs on a Dask cluster;
## DEVICE=cuda (or auto) trains them on a GPU; BOOK_ARGS="--data-dir DIR" keeps the caches in DIR.
book: $(BIN)/.installed
	$(BIN)/study book --preset $(PRESET) $(if $(SCHEDULER),--scheduler $(SCHEDULER)) --device $(DEVICE) $(BOOK_ARGS)

## Unit tests and smoke runs of the real entry points (smoke presets), in two processes (pytest-xdist): under
## 10 minutes on two cores. The whole smoke book and the README's recipes are test-book's.
test: $(BIN)/.installed
	$(BIN)/python -m pytest -n 2 --dist worksteal -m "not book"

## The whole book on the smoke preset, checked page by page, and every README recipe as written (about 15 minutes
## on two cores). CI runs it after `make test`.
test-book: $(BIN)/.installed
	$(BIN)/python -m pytest -n 2 --dist worksteal -m book

## Benchmarks: each prints a ratio against a plain baseline measured in the same run (bench_recipe.py aside: it
## trains networks, see bench-recipe).
bench: $(BIN)/.installed
	@for b in benchmarks/bench_*.py; do [ $$b = benchmarks/bench_recipe.py ] && continue; echo "== $$b"; $(BIN)/python $$b || exit 1; done

## Which training recipe settles: candidates on the networks that swing most, chosen on validation, then confirmed.
## RECIPE_ARGS="--preset paper --seeds 5 --confirm" asks the real question (hours on two cores); the default is a smoke run.
RECIPE_ARGS ?= --preset smoke
bench-recipe: $(BIN)/.installed
	$(BIN)/python benchmarks/bench_recipe.py $(RECIPE_ARGS)

clean:
	rm -rf _build
