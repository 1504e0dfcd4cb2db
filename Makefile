# affnerf: `make test` and `make demo` each set up a fresh machine on their own.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TORCH_PIN := torch==2.13.0
# the versions the committed results were measured with; `make install LOCK=` takes the newest instead
LOCK ?= requirements-lock.txt
CONSTRAINTS := $(if $(LOCK),-c $(LOCK))
DEMO_OUT ?= demo_out

.PHONY: install test lint format demo clean

install: $(STAMP)

# torch is installed first with its exact pin: a bare `torch` requirement would pull the CUDA build.
$(STAMP): pyproject.toml $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet $(TORCH_PIN) $(CONSTRAINTS)
	$(BIN)/pip install --quiet -e ".[dev,segment]" $(CONSTRAINTS)
	touch $(STAMP)

# the tests run on a pytest-xdist worker per core, each on one thread (tests/conftest.py); TEST_WORKERS=0 runs them
# in this one process
TEST_WORKERS ?= auto
test: install lint
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS)

# ruff: lint and formatting (settings in pyproject.toml); `make format` rewrites files in place.
lint: install
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: install
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

demo: install
	$(BIN)/affnerf demo --out $(DEMO_OUT)

clean:
	rm -rf $(VENV) $(DEMO_OUT) build *.egg-info src/*.egg-info
