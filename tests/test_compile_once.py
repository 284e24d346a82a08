"""Compile once (issue #10): after the first host call of `train`, a second one compiles nothing; a second
evaluation of the same song set, with other weights, compiles nothing either; two trainers for two songs of one
capacity lower to one program, whatever the process traced in between. Counted with JAX's own compile events
(`/jax/core/compile/backend_compile_duration`, one per XLA compilation or persistent-cache load: tests/conftest.py)."""
import hashlib
import os

import jax
import jax.numpy as jnp
import pytest


@pytest.fixture
def trainer(left_trainer):
    return left_trainer


def test_a_second_train_call_compiles_nothing(trainer, tmp_path, compiles_per_call):
    first, second = compiles_per_call(trainer, tmp_path / "run")
    assert first >= 1            # the run did compile (the count would see it) ...
    assert second == 0           # ... once


def test_a_second_evaluation_compiles_nothing(compiles):
    from dexguitar.learn import networks as N
    from dexguitar.learn import policy as PO
    from dexguitar.music import library
    from dexguitar.perform.evaluate import evaluate
    from dexguitar.envs.layout import ObsLayout
    spec = PO.PolicySpec("policy", "left", 27, ObsLayout(("left",), 2, 208, 35, 6))
    params = {"policy": N.init_params(N.Policy(27), jax.random.PRNGKey(0), (2, 208), (35,)),
              "obs_norm": N.normalizer_init(208)}
    song = library.load("open_strings")
    start = compiles()
    evaluate(params, spec, [song])
    other = jax.block_until_ready(jax.tree.map(lambda x: x + 0.01, params))   # other weights, the same program
    before = compiles()
    assert before > start                                               # the first evaluation compiled
    result = evaluate(other, spec, [library.load("twinkle")])          # another song of the same capacity
    assert compiles() == before
    (title, res), = result.items()
    f1 = res["summary"]["left"]["f1"]       # a random hand may fail before a note is judged: NaN, nothing to score
    assert title.startswith("Twinkle") and (f1 != f1 or 0.0 <= f1 <= 1.0)


def test_two_songs_of_a_capacity_share_one_program_whatever_was_traced_between(trainer):
    """`dexguitar songs --per-song` compiled the training chunk again for the second song (another persistent-cache
    key): JAX's tracing caches overflow within one chunk's trace, so the program depended on what the process had
    traced before, there the judge's evaluation. `learn.tracing` traces the chunk from empty caches."""
    from dexguitar import envs as E
    from dexguitar.learn.devices import Placement
    from dexguitar.learn.trainer import Trainer
    from dexguitar.motion import load_motion
    from dexguitar.motion.kinematics import reference_frames
    from dexguitar.music import library
    from dexguitar.music import timeline as TL
    other = Trainer(trainer.config, [TL.from_song(library.load("twinkle"))], reference_frames(load_motion("left")))
    assert other.data.songs.left.shape == trainer.data.songs.left.shape            # one capacity, other notes
    assert not jnp.array_equal(other.data.songs.left, trainer.data.songs.left)
    where = Placement()

    def lowered(t):     # (characters, private functions, digest) of the chunk `train` compiles for t
        shapes = jax.eval_shape(t.init)                    # as `train` places it, without computing it
        state = jax.tree.map(lambda s, sharding: jax.ShapeDtypeStruct(s.shape, s.dtype, sharding=sharding), shapes,
                             where.shardings(shapes))
        text = t.make_train_chunk(1, where).lower(state, where.put(t.data, where.replicated(t.data))).as_text()
        return len(text), text.count("func.func private"), hashlib.sha1(text.encode()).hexdigest()
    first = lowered(trainer)
    # what the judge does between two songs, in small: trace a step of an evaluation env (this alone gave the old
    # code another program for the next song: 596 private functions instead of 590)
    env = E.make("left", other.data.songs, E.EnvConfig().evaluation())
    jax.eval_shape(lambda k: env.step(env.reset(k), jnp.zeros(env.action_size)), jax.random.PRNGKey(0))
    assert lowered(other) == first
    # the state's first value has one program too: the songs are its arguments, not constants
    key = jax.random.PRNGKey(0)
    assert (trainer._init_program.lower(key, trainer.init_inputs()).as_text()
            == other._init_program.lower(key, other.init_inputs()).as_text())


@pytest.mark.parametrize("user, expected", [
    ("", "--xla_gpu_enable_triton_gemm=false"),
    ("--xla_force_host_platform_device_count=2", "--xla_force_host_platform_device_count=2 "
                                                 "--xla_gpu_enable_triton_gemm=false"),
    ("--xla_gpu_enable_triton_gemm=true", "--xla_gpu_enable_triton_gemm=true"),       # the user's choice stands
])
def test_commands_that_compile_turn_triton_gemms_off(monkeypatch, user, expected):
    """XLA reads XLA_FLAGS when its backend starts, so `main` sets the flag before the command runs (here a command
    that fails at once on a missing policy, after the flag is set)."""
    from dexguitar.cli import main
    monkeypatch.setenv("XLA_FLAGS", user)
    assert main(["eval", "--ckpt", "/nonexistent/policy", "--song", "ode_to_joy"]) == 2
    assert os.environ["XLA_FLAGS"] == expected
