# sonotrack: everything a fresh clone needs, from a machine with Python 3.11 and make.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
FMU_DIR := fmus
SCENARIO ?= scenarios/s_curve.toml

.PHONY: install fmus demo test test-unit benchmarks clean

install: $(STAMP)

# constraints.txt pins every package to the versions the project was tested with.
$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	$(BIN)/python -m pip install --quiet -c constraints.txt -e ".[test]"
	touch $(STAMP)

fmus: $(STAMP)
	$(BIN)/sonotrack build --out $(FMU_DIR)

demo: fmus
	$(BIN)/sonotrack run $(SCENARIO) --out runs/demo

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-unit: $(STAMP)
	$(BIN)/python -m pytest -q -m "not integration"

benchmarks: fmus
	for script in benchmarks/[!_]*.py; do $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) $(FMU_DIR)/*.fmu $(FMU_DIR)/*.ssp runs .pytest_cache
