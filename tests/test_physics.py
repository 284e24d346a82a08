"""The physics switch (`EnvConfig.physics`, `world.physics.resolve`): Warp only where it can run (a GPU), else JAX
with one line that says why; Warp's buffers sized from a run's envs per device (`EnvConfig.sized`); a selection between
states (`physics.where`) as `jnp.where` under JAX; stdout kept for a command's own output while the physics prints
(`physics.stdout_to_stderr`). No MJX compile."""
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


def on_a_gpu_with_warp(monkeypatch):
    """`physics.resolve` as on a GPU where warp-lang imports."""
    real = P.resolve
    monkeypatch.setattr(P, "resolve", lambda physics="auto": real(physics, installed=True, platform="gpu"))


def test_sized_sets_warp_envs_to_the_envs_of_one_device_under_warp_alone(monkeypatch, capsys):
    from dexguitar.envs import EnvConfig
    P.resolve.cache_clear()
    here = EnvConfig()
    assert here.sized(512) is here and EnvConfig(physics="warp").sized(512).physics == "jax"   # this CPU
    assert "runs as 'jax' here" in capsys.readouterr().err
    on_a_gpu_with_warp(monkeypatch)
    sized = EnvConfig().sized(512)
    assert (sized.physics, sized.warp_envs) == ("warp", 512)
    assert EnvConfig(physics="jax").sized(512) == EnvConfig(physics="jax")
    assert EnvConfig().sized(512, devices=2) == EnvConfig(physics="warp", warp_envs=256)   # each device's own
    assert EnvConfig(physics="warp").sized(512, devices=4) == EnvConfig(physics="warp", warp_envs=128)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("devices, warp_envs", [(1, 64), (2, 32), (4, 16)])
def test_a_trainer_sizes_warp_for_the_envs_of_one_device(devices, warp_envs, monkeypatch):
    import types

    from dexguitar.learn import trainer as T
    from dexguitar.music import library
    from dexguitar.music import timeline as TL

    class Made(Exception):
        pass

    def make(hand, songs, config):
        raise Made(config)
    on_a_gpu_with_warp(monkeypatch)
    monkeypatch.setattr(T.E, "make", make)
    monkeypatch.setattr(T, "Placement", lambda n: types.SimpleNamespace(n=n))     # as on `devices` GPUs
    with pytest.raises(Made) as made:
        T.Trainer(T.TrainConfig(num_envs=64, minibatch=64), [TL.from_song(library.load("ode_to_joy"))], None,
                  devices=devices)
    config = made.value.args[0]
    assert (config.physics, config.warp_envs, config.episode_frames) == ("warp", warp_envs, 600)


def test_stdout_to_stderr_keeps_stdout_for_the_document(capfd):
    import ctypes
    import os
    with P.stdout_to_stderr():
        print("from python")
        os.write(1, b"from fd 1\n")
        ctypes.CDLL(None).printf(b"from C's stdout\n")       # as the GPU's printf reaches the host: buffered
    print('{"f1": 1.0}')
    out, err = capfd.readouterr()
    assert out == '{"f1": 1.0}\n'
    assert all(line in err for line in ("from python", "from fd 1", "from C's stdout"))


def test_eval_json_stays_one_document_whatever_the_play_prints(monkeypatch, capfd):
    import json
    import os
    from types import SimpleNamespace
    from dexguitar import cli

    def evaluate(params, spec, songs, env_config=None, record=False):
        print("Warp 1.18.0 initialized")
        os.write(1, b"solver iterations limit reached - please increase iterations beyond 4\n")
        return {"Ode": {"summary": {"left": {"f1": 1.0}}, "notes": []}}
    monkeypatch.setattr(cli.PO, "load", lambda path: ({}, {"hand": "left"}))
    monkeypatch.setattr(cli.PO.PolicySpec, "from_meta", staticmethod(lambda meta: SimpleNamespace(kind="policy")))
    monkeypatch.setattr(cli, "evaluate", evaluate)
    assert cli.main(["eval", "--ckpt", "C", "--song", "ode_to_joy", "--json", "--physics", "warp"]) == 0
    out, err = capfd.readouterr()
    assert json.loads(out) == {"Ode": {"left": {"f1": 1.0}}}
    assert "solver iterations limit reached" in err and "initialized" in err


def test_the_env_states_are_split_over_devices_and_the_rest_is_whole():
    # Warp's buffers outside the env batch are split too: each device holds its own (`Trainer.reset_envs`)
    import jax
    from flax import struct
    from dexguitar.learn.devices import Placement

    @struct.dataclass
    class State:
        env: dict
        params: jax.Array
    where = Placement(1)
    got = where.shardings(State(env={"qpos": jnp.zeros((4, 3)), "nacon": jnp.zeros(1, jnp.int32)}, params=jnp.zeros(2)))
    assert got.env["qpos"] == where.split and got.env["nacon"] == where.split and got.params == where.whole


def test_a_run_made_before_the_physics_fields_resumes_under_jax_alone(tmp_path):
    import json
    from dexguitar.errors import RunError
    from dexguitar.learn.run import RunDir
    run = RunDir(tmp_path)
    try:
        run.config.write_text(json.dumps({"train": {"hand": "left"}, "env": {"shift_prob": 0.5}}))
        env = {"shift_prob": 0.5, "physics": "auto", "warp_envs": 4096}
        run.check_resume({"train": {"hand": "left"}, "env": env})
        with pytest.raises(RunError, match="env.physics: 'auto' -> 'warp'; env.warp_envs: 4096 -> 64"):
            run.check_resume({"train": {"hand": "left"}, "env": dict(env, physics="warp", warp_envs=64)})
    finally:
        run.close()


# Warp's buffers outside the env batch, on a stand-in for Warp's Data: `fills` and `refill` as an env's reset uses them
WARP_STANDIN = """
import dataclasses, hashlib
import jax, jax.numpy as jnp
from mujoco.mjx.warp.types import DATA_NON_VMAP
from dexguitar.world import physics as P

Impl = dataclasses.make_dataclass("Impl", sorted(DATA_NON_VMAP))
Impl.replace = dataclasses.replace
Data = dataclasses.make_dataclass("Data", ["impl", "_impl"])
Data.replace = dataclasses.replace
data = Data(impl=P.mjx.Impl.WARP, _impl=Impl(**{n: jnp.full((3, i + 2), i, jnp.int32) for i, n in
                                                enumerate(sorted(DATA_NON_VMAP))}))
fills = P.fills(data)
text = jax.jit(lambda: dataclasses.asdict(P.refill(data, fills)._impl)).lower().as_text()
print(",".join(fills), hashlib.sha256(text.encode()).hexdigest())
"""


def test_warp_buffers_are_made_in_one_order_in_every_process():
    """MJX names Warp's shared buffers in a set, whose order follows Python's string hashing, which changes from
    process to process. A reset made them in that order, so each run lowered another program, which JAX's persistent
    cache did not serve: a later run under Warp compiled its training chunk again. Two processes with other hash
    seeds make the same program, the buffers in sorted order."""
    import os
    import subprocess
    import sys
    from mujoco.mjx.warp.types import DATA_NON_VMAP
    outs = set()
    for seed in ("1", "2"):
        done = subprocess.run([sys.executable, "-c", WARP_STANDIN], env=dict(os.environ, PYTHONHASHSEED=seed,
                              JAX_PLATFORMS="cpu"), capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr[-2000:]
        outs.add(done.stdout.strip().splitlines()[-1])
    assert len(outs) == 1, outs
    assert outs.pop().split()[0].split(",") == sorted(DATA_NON_VMAP)
