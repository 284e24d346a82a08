# Every target sets up .venv first (once), then calls the `dexguitar` command.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: setup demo test check models clean

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $(STAMP)

setup: $(STAMP)                ## make the virtual environment and install the package

demo: $(STAMP)                 ## the main job on the embedded defaults
	$(BIN)/dexguitar check

test: $(STAMP)                 ## the CPU test suite
	JAX_PLATFORMS=cpu $(BIN)/python -m pytest

check: demo

models: $(STAMP)               ## regenerate models/*.xml from dexguitar/world
	$(BIN)/python -m dexguitar.world.hands
	$(BIN)/python -c "from dexguitar.world import scene; [print('wrote', p) for p in scene.write_models()]"

clean:
	rm -rf $(VENV) .pytest_cache
