"""Compile once (issue #10): after the first host call of `train`, a second one compiles nothing; a second
evaluation of the same song set, with other weights, compiles nothing either; two trainers for two songs of one
capacity lower to one program, whatever the process traced in between. Counted with JAX's own compile events
(`/jax/core/compile/backend_compile_duration`, one per XLA compilation or persistent-cache load: tests/conftest.py)."""
import dataclasses
import hashlib
import json
import os

import jax
import jax.numpy as jnp
import pytest


@pytest.fixture
def trainer(left_trainer):
    return left_trainer


def test_a_second_call_compiles_nothing_and_a_later_run_in_the_process_reuses_its_chunk(trainer, tmp_path,
                                                                                        monkeypatch, compiles,
                                                                                        export_compiles):
    """Within a run, the second host call of `train` compiles nothing. A second run of the same code, config and
    shapes in one process (`dexguitar songs`: the next song of a capacity) takes the chunk the first one compiled
    or loaded from its file (`learn.executable`): nothing traced, lowered, compiled or loaded, and the same numbers."""
    from dexguitar.learn import executable as X
    from dexguitar.learn import run as RUN
    from dexguitar.learn.trainer import Trainer
    monkeypatch.setattr(X, "_LIVE", {})         # the first run compiles or loads its chunk, not take an earlier test's

    def train(out, iterations):
        logs = []
        RUN.train(trainer, tmp_path / out, iterations=iterations, progress=False, log=logs.append)
        rows = [json.loads(line) for line in (tmp_path / out / "metrics.jsonl").read_text().splitlines()]
        return logs, json.dumps([{k: v for k, v in r.items() if k not in ("seconds", "samples_per_s", "wall",
                                                                           "compile_s", "ckpt_s", "compact_s")}
                                 for r in rows[:1]])        # as text: F1 is NaN before a note is judged

    start = compiles()
    logs, first = train("a", 2)                     # two host calls (`iterations_per_call` 1)
    assert any(m.startswith(("compiled the training chunk", "loaded the training chunk")) for m in logs)
    assert len(export_compiles) == 2 and export_compiles[0] > start    # the first call got it (the count sees it)
    assert export_compiles[1] == export_compiles[0]                     # ... and the second nothing

    def no_trace(*args, **kwargs):
        raise AssertionError("the chunk was traced")
    monkeypatch.setattr(Trainer, "make_train_chunk", no_trace)
    before = compiles()
    logs, second = train("b", 1)
    assert any(m.startswith("reused the training chunk") for m in logs) and compiles() == before
    assert second == first


@dataclasses.dataclass(frozen=True)
class StubConfig:
    scale: float = 2.0
    seed: int = 0
    iterations: int = 10


class StubTrainer:
    """What `learn.executable` reads of a trainer, around a chunk that compiles in milliseconds."""

    def __init__(self, scale: float = 2.0, **config):
        self.config, self.env, self.spec, self.traced = StubConfig(scale, **config), StubEnv(), "stub", 0

    def make_train_chunk(self, n, where):
        from dexguitar.learn.stages import Stages
        self.traced += 1
        scale = self.config.scale
        return Stages([jax.jit(lambda state, data: jnp.tanh(state * scale + data)),      # n iterations of two
                       jax.jit(lambda state, data: (state, {"sum": jnp.sum(state)}))], n)


class StubEnv:
    config = StubConfig(0.0)
    physics = "jax"


STUB_RUN = """
import json, sys
from pathlib import Path
sys.path.insert(0, sys.argv[2])
import jax, jax.numpy as jnp
from dexguitar.learn import executable as X
from dexguitar.learn.devices import Placement
from test_compile_once import StubTrainer
X.directory = lambda: Path(sys.argv[1])
trainer = StubTrainer()
state = jax.ShapeDtypeStruct((8,), jnp.float32)
build = X.ChunkBuild(trainer, Placement(), 3, state, jnp.linspace(-1, 1, 8), print)
compiled, seconds, how = build.result()
print(json.dumps({"how": how, "traced": trainer.traced,
                  "out": compiled(jnp.arange(8, dtype=jnp.float32) / 8, jnp.linspace(-1, 1, 8))[0].tolist()}))
"""


def test_a_chunk_file_loads_in_a_new_process_without_tracing(tmp_path, monkeypatch):
    """The first build of a chunk keeps it in a file; a new process loads it without tracing it and computes the
    same; a file that does not load is compiled again; another config, other XLA flags or another number of
    iterations per call is another file, another seed or run length is not; on XLA:CPU a chunk that came from JAX's
    persistent cache is not kept."""
    import subprocess
    import sys
    from dexguitar.learn import executable as X
    from dexguitar.learn.devices import Placement
    monkeypatch.setattr(X, "directory", lambda: tmp_path)
    monkeypatch.setattr(X, "_LIVE", {})
    state, data = jax.ShapeDtypeStruct((8,), jnp.float32), jnp.linspace(-1, 1, 8)
    x = jnp.arange(8, dtype=jnp.float32) / 8
    expected = x
    for _ in range(3):
        expected = jnp.tanh(expected * 2.0 + data)

    def build(trainer, n=3):
        return X.ChunkBuild(trainer, Placement(), n, state, data, logs.append).result()

    logs, trainer = [], StubTrainer()
    compiled, _, how = build(trainer)
    files = list(tmp_path.glob("chunk-*.exe"))
    assert how == "compiled" and trainer.traced == 1 and len(files) == 1
    assert jnp.allclose(compiled(x, data)[0], expected)

    def run():
        done = subprocess.run([sys.executable, "-c", STUB_RUN, str(tmp_path), os.path.dirname(__file__)],
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr[-3000:]
        return json.loads(done.stdout.splitlines()[-1])
    out = run()
    assert out["how"] == "loaded" and out["traced"] == 0
    assert jnp.allclose(jnp.asarray(out["out"]), expected)

    files[0].write_bytes(b"not an executable")
    out = run()
    assert out["how"] == "compiled" and out["traced"] == 1 and jnp.allclose(jnp.asarray(out["out"]), expected)

    where = Placement()
    base = X.key(trainer, where, 3, (state, data))
    assert X.key(StubTrainer(3.0), where, 3, (state, data)) != base
    # what the chunk does not read: another seed or a longer run loads the same file
    assert X.key(StubTrainer(seed=7, iterations=99), where, 3, (state, data)) == base
    assert X.key(trainer, where, 4, (state, data)) != base
    with monkeypatch.context() as m:
        m.setenv("XLA_FLAGS", os.environ.get("XLA_FLAGS", "") + " --xla_cpu_enable_fast_math=false")
        assert X.key(trainer, where, 3, (state, data)) != base

    # from JAX's persistent cache: a program of 5 iterations compiled once into it, then again out of it
    least = jax.config.jax_persistent_cache_min_compile_time_secs
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    try:
        build(StubTrainer(), 5)
        for f in tmp_path.glob("chunk-*.exe"):
            f.unlink()
        monkeypatch.setattr(X, "_LIVE", {})
        compiled, _, how = build(StubTrainer(), 5)
    finally:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", least)
    assert how == "compiled" and not list(tmp_path.glob("chunk-*.exe"))


def test_a_second_evaluation_compiles_nothing_and_a_learned_hand_plans_nothing(compiles, monkeypatch):
    """A policy that is not a residual (`left_learned`'s kind) acts from its network alone: nothing of the planner
    runs while it plays (every way into the planner raises)."""
    from dexguitar import planner
    from dexguitar.learn import networks as N
    from dexguitar.learn import policy as PO
    from dexguitar.music import library
    from dexguitar.perform.evaluate import evaluate
    from dexguitar.envs.layout import ObsLayout
    spec = PO.PolicySpec("policy", "left", 27, ObsLayout(("left",), 2, 208, 35, 6))
    params = {"policy": N.init_params(N.Policy(27), jax.random.PRNGKey(0), (2, 208), (35,)),
              "obs_norm": N.normalizer_init(208)}
    song = library.load("open_strings")

    def planning(*args, **kwargs):
        raise AssertionError("the planner ran")
    for module in (planner, planner.plans):
        for name in ("attach", "plan_songs"):
            monkeypatch.setattr(module, name, planning)
    for name in ("plan_notes", "plan_all", "_planner"):
        monkeypatch.setattr(planner.plans, name, planning)
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
        state = where.placed_shapes(jax.eval_shape(t.init))      # as `train` places it, without computing it
        text = "".join(program.as_text() for program in
                       t.make_train_chunk(1, where).lower(state, where.put(t.data, where.replicated(t.data))))
        return len(text), text.count("func.func private"), hashlib.sha1(text.encode()).hexdigest()
    first = lowered(trainer)
    # what the judge does between two songs, in small: trace a step of an evaluation env (this alone gave the old
    # code another program for the next song: 596 private functions instead of 590)
    env = E.make("left", other.data.songs, E.EnvConfig().evaluation())
    jax.eval_shape(lambda k: env.step(env.reset(k), jnp.zeros(env.action_size)), jax.random.PRNGKey(0))
    assert lowered(other) == first
    # the state's first value has one program too: the songs are its arguments, not constants
    key = jax.random.PRNGKey(0)
    nets = jax.eval_shape(trainer.initial_params, key, trainer.init_inputs())
    assert (trainer._params_program.lower(key, trainer.init_inputs()).as_text()
            == other._params_program.lower(key, other.init_inputs()).as_text())
    assert (trainer._init_program.lower(key, trainer.init_inputs(), nets).as_text()
            == other._init_program.lower(key, other.init_inputs(), nets).as_text())


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
