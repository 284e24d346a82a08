"""The physics switch (`EnvConfig.physics`, `world.physics.resolve`): Warp only where it can run, else JAX with one
line that says why; a selection between states (`physics.where`) as `jnp.where` under JAX. No MJX compile."""
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar.world import physics as P


def resolve(physics, capsys, **here):
    P.resolve.cache_clear()
    out = P.resolve(physics, **here)
    return out, capsys.readouterr().err.splitlines()


@pytest.mark.parametrize("here, why", [({"installed": False, "platform": "gpu"}, "warp-lang is not installed"),
                                       ({"installed": False, "platform": "cpu"}, "warp-lang is not installed"),
                                       ({"installed": True, "platform": "cpu"}, "no GPU")])
def test_warp_where_it_cannot_run_is_jax_with_one_line(here, why, capsys):
    physics, err = resolve("warp", capsys, **here)
    assert physics == "jax"
    assert len(err) == 1 and err[0].startswith("warning: ") and why in err[0]
    assert resolve("auto", capsys, **here) == ("jax", [])          # auto falls back without a word
    assert resolve("jax", capsys, **here) == ("jax", [])


def test_this_machine_and_a_gpu_with_warp(capsys):
    assert resolve("auto", capsys) == ("jax", [])                  # the suite runs on a CPU
    physics, err = resolve("warp", capsys)
    assert physics == "jax" and len(err) == 1
    assert P.resolve("warp") == "jax" and capsys.readouterr().err == ""   # said once per process
    assert resolve("auto", capsys, installed=True, platform="gpu") == ("warp", [])
    assert resolve("warp", capsys, installed=True, platform="gpu") == ("warp", [])
    with pytest.raises(ValueError, match="physics 'mujoco'"):
        P.resolve("mujoco")


def test_where_selects_leaves_by_a_scalar_or_a_batch_mask():
    a = {"x": jnp.ones((3, 2)), "n": jnp.arange(3)}
    b = {"x": jnp.zeros((3, 2)), "n": -jnp.arange(3)}
    out = P.where(jnp.array([True, False, True]), a, b)
    np.testing.assert_array_equal(out["x"], [[1, 1], [0, 0], [1, 1]])
    np.testing.assert_array_equal(out["n"], [0, -1, 2])
    np.testing.assert_array_equal(P.where(False, a, b)["x"], b["x"])


def test_an_env_asked_for_warp_runs_jax_here(capsys):
    from dexguitar import envs, mjx
    from dexguitar.music import library
    P.resolve.cache_clear()
    env = envs.make("left", [library.load("ode_to_joy")], physics="warp")
    assert env.physics == "jax" and env.mjx_model.impl == mjx().Impl.JAX
    assert "warning: physics 'warp' runs as 'jax' here" in capsys.readouterr().err
