# Every target sets up .venv first (once), then calls the `dexguitar` command.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: setup demo test check models clean train-left train-right sync eval plot
SONG ?= ode_to_joy
CONFIG_LEFT ?= experiments/left_gpu.py
CONFIG_RIGHT ?= experiments/right_gpu.py
CONFIG_SYNC ?= experiments/sync_gpu.py
LEFT ?= models/policies/left_$(SONG)
RIGHT ?= models/policies/right_patterns
OUT ?= runs

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev,video,plot]"
	@# offscreen OpenGL for rendering (OSMesa or EGL); installed from Debian's packages when missing and possible
	@$(PY) -c "import ctypes.util as u, sys; sys.exit(0 if u.find_library('OSMesa') or u.find_library('EGL') else 1)" \
	  || (command -v apt-get >/dev/null && [ "$$(id -u)" = 0 ] && (apt-get update -qq && apt-get install -y -qq libosmesa6) >/dev/null) \
	  || echo "warning: no offscreen OpenGL (install libosmesa6 or libegl1): videos cannot be rendered"
	touch $(STAMP)

setup: $(STAMP)                ## make the virtual environment and install the package

demo: $(STAMP)                 ## the main job: the shipped synchronized policies play a song -> out/demo.mp4, .wav, report
	$(BIN)/dexguitar song list
	$(BIN)/dexguitar play --ckpt models/policies/sync_strum_g_c_d --song strum_g_c_d --out out/demo

test: $(STAMP)                 ## the CPU test suite
	JAX_PLATFORMS=cpu $(BIN)/python -m pytest

check: $(STAMP)                ## every scene steps in MJX (4 envs, jit + vmap)
	$(BIN)/dexguitar check

train-left: $(STAMP)           ## make train-left SONG="ode_to_joy twinkle" [MOTION=retargeted.npz] [RESUME=1]
	$(BIN)/dexguitar train --hand left --song $(SONG) --config $(CONFIG_LEFT) \
	  --out $(OUT)/left-$(firstword $(notdir $(SONG))) $(if $(MOTION),--motion $(MOTION)) $(if $(RESUME),--resume)

train-right: $(STAMP)          ## procedural picking and strumming patterns
	$(BIN)/dexguitar train --hand right --config $(CONFIG_RIGHT) --out $(OUT)/right $(if $(RESUME),--resume)

sync: $(STAMP)                 ## make sync SONG=strum_g_c_d [LEFT=dir] [RIGHT=dir] [RESUME=1]: both hands in time
	$(BIN)/dexguitar sync --song $(SONG) --left $(LEFT) --right $(RIGHT) --config $(CONFIG_SYNC) \
	  --out $(OUT)/sync-$(firstword $(notdir $(SONG))) $(if $(RESUME),--resume)

eval: $(STAMP)                 ## make eval CKPT=models/policies/left_ode_to_joy SONG=ode_to_joy
	$(BIN)/dexguitar eval --ckpt $(CKPT) --song $(SONG)

models: $(STAMP)               ## regenerate models/*.xml from dexguitar/world
	$(BIN)/python -m dexguitar.world.hands
	$(BIN)/python -c "from dexguitar.world import scene; [print('wrote', p) for p in scene.write_models()]"

clean:
	rm -rf $(VENV) .pytest_cache
