"""Compile once (issue #10): after the first host call of `train`, a second one compiles nothing; a second
evaluation of the same song set, with other weights, compiles nothing either. Counted with JAX's own compile events
(`/jax/core/compile/backend_compile_duration`, one per XLA compilation: tests/conftest.py)."""
import jax
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
