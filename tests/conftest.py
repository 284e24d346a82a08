"""Test-wide settings: a persistent XLA compilation cache, so that a computation compiled by one test (or an earlier
run of the suite) is not compiled again by the next one; the suite is dominated by compiling the scanned envs.
Rendering tests take the `offscreen_gl` fixture."""
import os
from pathlib import Path

import jax
import pytest

CACHE = Path(os.environ.get("DEXGUITAR_TEST_CACHE", Path(__file__).resolve().parent.parent / ".cache" / "xla"))
jax.config.update("jax_compilation_cache_dir", str(CACHE))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 2.0)
# the commands that tests call (`cli.main`) set their own cache from DEXGUITAR_CACHE: the same one
os.environ["DEXGUITAR_CACHE"] = str(CACHE)


COMPILES = []          # one entry per XLA compilation (JAX's own event), for the compile-once tests
jax.monitoring.register_event_duration_secs_listener(
    lambda name, secs, **kw: COMPILES.append(name) if name == "/jax/core/compile/backend_compile_duration" else None)


@pytest.fixture
def compiles():
    """The number of XLA compilations so far in this process."""
    return lambda: len(COMPILES)


@pytest.fixture
def compiles_per_call(compiles, monkeypatch):
    """run(trainer, out, calls=2) -> the number of compilations of each host call of `train`, counted from the end
    of one call (its export) to the end of the next (the first count includes building the run)."""
    from dexguitar.learn import checkpoint as C
    from dexguitar.learn import run as RUN

    def run(trainer, out, calls: int = 2) -> list[int]:
        counts, save = [], C.save

        def counting_save(directory, *args, **kwargs):
            out = save(directory, *args, **kwargs)
            if Path(directory).parent.name == "policy":  # the export: the last thing a host call does
                counts.append(compiles())
            return out
        monkeypatch.setattr(C, "save", counting_save)
        start = compiles()
        RUN.train(trainer, out, iterations=calls, progress=False, log=lambda m: None)
        return [b - a for a, b in zip([start] + counts[:-1], counts)]
    return run


@pytest.fixture(scope="session")
def compiled_chunk():
    """compiled_chunk(trainer, state): one training iteration compiled as `train` compiles it (placed, ahead of
    time), so that tests calling it directly share `train`'s program through the persistent cache.
    -> (chunk, state, data, put): the state and data placed, and `put` to place another (restored) state alike."""
    from dexguitar.learn.devices import Placement

    def build(trainer, state):
        where = Placement()
        shardings = where.shardings(state)
        state, data = where.put(state, shardings), where.put(trainer.data, where.replicated(trainer.data))
        chunk = trainer.make_train_chunk(1, where).lower(state, data).compile()
        return chunk, state, data, lambda tree: where.put(tree, shardings)
    return build


@pytest.fixture(scope="session")
def left_trainer():
    """The tiny left-hand trainer that several test files share (4 envs, one song): one compiled program for all."""
    from dexguitar.learn.trainer import Trainer, TrainConfig
    from dexguitar.motion import load_motion
    from dexguitar.motion.kinematics import reference_frames
    from dexguitar.music import library
    from dexguitar.music import timeline as TL
    cfg = TrainConfig(num_envs=4, horizon=4, minibatch=8, epochs=2, disc_steps=2, disc_buffer=64, disc_batch=16,
                      iterations_per_call=1)
    return Trainer(cfg, [TL.from_song(library.load("ode_to_joy"))], reference_frames(load_motion("left")))


@pytest.fixture(scope="session")
def offscreen_gl() -> str:
    """The offscreen OpenGL backend that rendering tests draw with. Without one a rendering test is skipped, except
    under CI (`CI=true`), where it fails: a green CI must mean that the videos render (issue #14)."""
    from dexguitar.motion import glcheck
    try:
        return glcheck.backend()
    except glcheck.NoGL as err:
        if os.environ.get("CI", "").lower() in ("true", "1"):
            pytest.fail(f"CI without an offscreen OpenGL: {err}")
        pytest.skip(str(err))
