# Every target sets up .venv first (once), then calls the `dexguitar` command.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: setup demo test check models clean train-left train-left-general train-right sync songs eval plot
SONG ?= ode_to_joy
CONFIG_LEFT ?= left_gpu
CONFIG_RIGHT ?= right_gpu
CONFIG_SYNC ?= sync_hold
# make sync: the general pair (GSync) unless LEFT=/RIGHT= name others
LEFT ?= models/policies/left_general
RIGHT ?= models/policies/right_mixed
OUT ?= runs
# test processes (compilation is single-threaded: one per core)
JOBS ?= 2

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev,video,plot]"
	@# Offscreen OpenGL for the videos, tried for real (a context that draws, not a library on disk): OSMesa, the
	@# fastest on a CPU, is installed from Debian's packages when it does not draw and we are root. Then one line
	@# says what renders, or what to install (`make demo` writes the audio and the report either way).
	@$(BIN)/python -m dexguitar.motion.glcheck osmesa >/dev/null \
	  || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null && echo "installing libosmesa6 (offscreen OpenGL)" \
	       && apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libosmesa6 >/dev/null 2>&1; } \
	  || true
	@$(BIN)/python -m dexguitar.motion.glcheck || true
	touch $(STAMP)

setup: $(STAMP)                ## make the virtual environment and install the package

demo: $(STAMP)                 ## the main job: the shipped synchronized policies play a song -> out/demo.mp4, .wav, report
	$(BIN)/dexguitar play --ckpt models/policies/sync_strum_g_c_d --song strum_g_c_d --out out/demo --caption

test: $(STAMP)                 ## the CPU test suite
	JAX_PLATFORMS=cpu $(BIN)/python -m pytest -n $(JOBS) --dist loadfile -rs

check: $(STAMP)                ## every scene steps in MJX (4 envs, jit + vmap)
	$(BIN)/dexguitar check

train-left: $(STAMP)           ## make train-left SONG="ode_to_joy twinkle" [MOTION=retargeted.npz] [RESUME=1]
	$(BIN)/dexguitar train --hand left --song $(SONG) --config $(CONFIG_LEFT) \
	  --out $(OUT)/left-$(firstword $(notdir $(SONG))) $(if $(MOTION),--motion $(MOTION)) $(if $(RESUME),--resume)

train-left-general: $(STAMP)   ## the general left hand: a residual held to the planner by a prior, balanced procedural material [RESUME=1]
	$(BIN)/dexguitar train --hand left --style general --procedural 256 --config left_general_anchored \
	  --out $(OUT)/left-general $(if $(RESUME),--resume) $(if $(DEVICES),--devices $(DEVICES))

train-right: $(STAMP)          ## procedural picking and strumming patterns
	$(BIN)/dexguitar train --hand right --config $(CONFIG_RIGHT) --out $(OUT)/right $(if $(RESUME),--resume)

sync: $(STAMP)                 ## make sync SONG=tab [LEFT=dir] [RIGHT=dir] [RESUME=1]: both hands in time (GSync default)
	$(BIN)/dexguitar sync --song $(SONG) --left $(LEFT) --right $(RIGHT) --config $(CONFIG_SYNC) \
	  --out $(OUT)/sync-$(firstword $(notdir $(SONG))) $(if $(RESUME),--resume)

songs: $(STAMP)                ## make songs SONGS="../shared/data/official/notes/*.json": tabs -> synchronized pair -> F1 table
	$(BIN)/dexguitar songs $(SONGS) --out $(OUT)/songs $(if $(PER_SONG),--per-song)

eval: $(STAMP)                 ## make eval CKPT=models/policies/left_ode_to_joy SONG=ode_to_joy
	$(BIN)/dexguitar eval --ckpt $(CKPT) --song $(SONG)

models: $(STAMP)               ## regenerate models/*.xml from dexguitar/world
	$(BIN)/python -m dexguitar.world.hands
	$(BIN)/python -c "from dexguitar.world import scene; [print('wrote', p) for p in scene.write_models()]"

clean:
	rm -rf $(VENV) .pytest_cache
