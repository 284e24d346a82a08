"""Faults survived and bad input refused (issue #14): non-finite numbers in training, a damaged checkpoint, a save
written in the background while training goes on or killed half-written, a full disk, a run directory in use or made
with another setup, a kill between a checkpoint and its metrics row or before the first checkpoint, a Ctrl-C or SIGTERM
while training (the chunk ends and is saved), and every command given bad paths: one line and exit code 2, never a
traceback. The training runs share the tiny left-hand trainer of tests/test_learn.py (same program, so the
persistent compilation cache serves it)."""
import errno
import gc
import json
import logging
import os
import shutil
import signal

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from dexguitar.cli import main
from dexguitar.errors import RunError, TrainingDiverged
from dexguitar.learn import checkpoint as C
from dexguitar.learn import run as RUN


@pytest.fixture
def trainer(left_trainer):
    return left_trainer


def poison(tree, value=jnp.nan):
    """The same pytree with the first number of every float leaf set to `value`."""
    return jax.tree.map(lambda x: x.reshape(-1).at[0].set(value).reshape(x.shape)
                        if jnp.issubdtype(x.dtype, jnp.floating) and x.size else x, tree)


def finite(tree):
    return all(bool(np.all(np.isfinite(np.asarray(x)))) for x in jax.tree.leaves(tree)
               if np.issubdtype(np.asarray(x).dtype, np.floating))


def test_an_env_with_nan_physics_is_reset_and_learning_stays_finite(trainer, compiled_chunk):
    state = trainer.init()
    data = state.env.body.data
    state = state.replace(env=state.env.replace(body=state.env.body.replace(
        data=data.replace(qvel=data.qvel.at[2, 0].set(jnp.nan)))))         # env 2 of 4 explodes at its next step
    chunk, state, data, _ = compiled_chunk(trainer, state)
    new, metrics = chunk(state, data)
    assert float(metrics["nonfinite/env_steps"]) == 1.0                     # found where it arose ...
    assert float(metrics["nonfinite/state"]) == 0.0
    assert finite(new.params) and finite(new.env.body.data.qpos)            # ... and contained: nothing else is NaN


def test_nonfinite_parameters_roll_back_and_are_never_saved(trainer, tmp_path, monkeypatch):
    fresh = trainer.init
    calls = []
    trainer.state_shapes        # the chunk's shapes (`jax.eval_shape` of `init`) taken now: the first real call poisons

    def init_poisoned_once(key=None):
        calls.append(1)
        state = fresh(key)
        return state.replace(params=dict(state.params, policy=poison(state.params["policy"]))) if len(
            calls) == 1 else state
    monkeypatch.setattr(trainer, "init", init_poisoned_once)
    messages = []
    RUN.train(trainer, tmp_path / "run", iterations=2, progress=False, save_every=0, log=messages.append)
    assert any("rolled back" in m for m in messages)
    # every saved step and the export are finite, and the run still reached its iterations
    steps = C.steps(tmp_path / "run" / "ckpt")
    assert steps == [2, 1]
    restored, _ = C.restore(tmp_path / "run" / "ckpt", fresh())
    assert finite(restored.params) and int(restored.iteration) == 2


def test_repeated_nonfinite_parameters_stop_the_run(trainer, tmp_path, monkeypatch):
    fresh = trainer.init
    monkeypatch.setattr(trainer, "init", lambda key=None: (lambda s: s.replace(
        params=dict(s.params, policy=poison(s.params["policy"]))))(fresh(key)))
    with pytest.raises(TrainingDiverged, match="non-finite"):
        RUN.train(trainer, tmp_path / "run", iterations=2, progress=False, log=lambda m: None)
    assert C.steps(tmp_path / "run" / "ckpt") == []                        # nothing non-finite was saved


def test_a_damaged_latest_checkpoint_falls_back_to_the_previous_one(tmp_path, capsys):
    tree = {"a": jnp.arange(4.0), "b": jnp.ones((2, 3))}
    C.save(tmp_path, 1, tree)
    C.save(tmp_path, 2, jax.tree.map(lambda x: x + 1, tree))
    # truncate every data file of step 2 (a disk that filled up, a copy cut short)
    for f in (tmp_path / "2").rglob("*"):
        if f.is_file() and f.stat().st_size > 64 and "d" == f.parent.name:
            f.write_bytes(f.read_bytes()[:16])
    restored, step = C.restore(tmp_path, jax.tree.map(jnp.zeros_like, tree))
    assert step == 1 and np.array_equal(restored["a"], np.arange(4.0))
    assert "step 2 cannot be read" in capsys.readouterr().err
    shutil.rmtree(tmp_path / "1")
    with pytest.raises(RunError, match="no intact checkpoint"):
        C.restore(tmp_path, tree)


def _damage(path, how):
    if how == "deleted":
        path.unlink()
    else:                                   # cut in half: a copy or a write cut short
        path.write_bytes(path.read_bytes()[:path.stat().st_size // 2])


def test_a_damaged_newest_step_any_file_is_set_aside_and_written_again(tmp_path):
    """Every file of the newest step, deleted or cut in half: either the step still restores exactly what was saved,
    or the step before it comes back, the damaged one is renamed out of orbax's steps and the run writes that step
    again (orbax refuses to write a step that exists)."""
    one = {"a": jnp.arange(5000.0), "b": jnp.ones((2, 3)), "c": jnp.int32(7)}
    two = jax.tree.map(lambda x: x + 1, one)
    base = tmp_path / "base"
    C.save(base, 1, one)
    C.save(base, 2, two)
    template = jax.tree.map(jnp.zeros_like, one)
    files = sorted(f.relative_to(base / "2") for f in (base / "2").rglob("*") if f.is_file())
    fell_back = set()
    for f in files:
        for how in ("deleted", "halved"):
            case = tmp_path / f"{how}-{str(f).replace('/', '_')}"
            shutil.copytree(base, case)
            _damage(case / "2" / f, how)
            restored, step = C.restore(case, template, set_damaged_aside=True)
            if step == 2:                                           # the damage did not touch what is read
                assert all(np.array_equal(restored[k], two[k]) for k in one), (f, how)
                continue
            fell_back.add((str(f), how))
            assert step == 1 and all(np.array_equal(restored[k], one[k]) for k in one), (f, how)
            assert C.steps(case) == [1] and [p.name[:10] for p in case.glob("2.*")] == ["2.damaged-"]
            if len(fell_back) > 1:
                continue
            with C.Saver(case) as saver:                            # the run goes on past the damaged step
                saver.save(2, jax.tree.map(lambda x: 3 * x, one))
                saver.save(3, jax.tree.map(lambda x: 4 * x, one))
            assert C.steps(case) == [3, 2]
            np.testing.assert_array_equal(C.restore(case, template)[0]["a"], 4 * np.arange(5000.0))
            np.testing.assert_array_equal(C.restore(case, template, step=2)[0]["a"], 3 * np.arange(5000.0))
    data = [str(f) for f in files if f.parent.name == "d"]
    # the manifests and the data files that hold the values cannot be lost without the fall-back
    assert {("default/manifest.ocdbt", h) for h in ("deleted", "halved")} <= fell_back
    assert any((d, "halved") in fell_back for d in data) and any((d, "deleted") in fell_back for d in data)


def test_a_resumed_run_goes_past_its_damaged_newest_checkpoint(trainer, tmp_path):
    """The newest checkpoint, that of the run's last iteration, has a data file cut in half: --resume restores the one
    before, sets the damaged one aside and trains that iteration again (a step orbax would refuse to write where it
    exists)."""
    run = tmp_path / "run"
    RUN.train(trainer, run, iterations=2, progress=False, save_every=0, log=lambda m: None)
    files = [f for f in (run / "ckpt" / "2").rglob("*") if f.is_file()]
    _damage(max(files, key=lambda f: f.stat().st_size), "halved")
    messages = []
    summary = RUN.train(trainer, run, iterations=2, resume=True, progress=False, log=messages.append)
    assert "resumed" in messages[0] and "at iteration 1" in messages[0]
    assert summary["iteration"] == 2 and summary["calls"] == 1
    assert C.steps(run / "ckpt") == [2, 1] and len(list((run / "ckpt").glob("2.damaged-*"))) == 1
    restored, step = C.restore(run / "ckpt", trainer.init())
    assert step == 2 and int(restored.iteration) == 2 and finite(restored.params)
    assert [json.loads(r)["iteration"] for r in (run / "metrics.jsonl").read_text().splitlines()] == [1, 2]


class FullDisk:
    """Orbax's background write of a step's `_METADATA` (a write of every save) into `directory`, from step `full`
    on, writes half of it and then fails as a full disk does."""

    def __init__(self, monkeypatch, directory, full: int):
        from etils import epath
        self.hits = []
        write = epath.Path.write_text

        def write_text(path, text, *args, **kwargs):
            name = str(path)
            if name.startswith(str(directory)) and name.endswith("/_METADATA") and int(
                    name[len(str(directory)) + 1:].split(".")[0]) >= full:
                self.hits.append(name)
                write(path, text[:len(text) // 2], *args, **kwargs)
                raise OSError(errno.ENOSPC, "No space left on device", name)
            return write(path, text, *args, **kwargs)
        monkeypatch.setattr(epath.Path, "write_text", write_text)


def test_abandoned_reads_of_a_damaged_checkpoint_log_nothing(caplog):
    """asyncio reports each read that orbax abandoned when a damaged checkpoint failed to restore, when the read is
    collected, which may be long after the restore (in another test here). Those reports are dropped; asyncio's
    others are kept."""
    failed = ("Future exception was never retrieved\nfuture: <Future finished exception=ValueError('OUT_OF_RANGE: "
              "Error reading \"00224/0.0\" in OCDBT database at local file \"/run/ckpt/2/default/\": Requested byte "
              "range [27881812, 28080274) is not valid for value of size 14084096')>")
    other = "Future exception was never retrieved\nfuture: <Future finished exception=ValueError('unrelated')>"
    with caplog.at_level(logging.ERROR, logger="asyncio"):
        logging.getLogger("asyncio").error(failed)
        logging.getLogger("asyncio").error(other)
    assert [r.getMessage() for r in caplog.records] == [other]


def test_collecting_abandoned_reads_warns_nothing(recwarn):
    """A read that orbax abandoned before it started is a coroutine never awaited: collected plainly, it warns."""
    def abandon():
        async def read():
            return None
        cycle = [read()]
        cycle.append(cycle)                      # freed only by the garbage collector
    abandon()
    with pytest.warns(RuntimeWarning, match="never awaited"):
        gc.collect()
    recwarn.clear()
    abandon()
    C.collect_abandoned()
    assert not [w for w in recwarn if "never awaited" in str(w.message)]


def test_a_full_disk_ends_a_save_in_one_error_and_keeps_the_step_before(tmp_path, monkeypatch, capfd, caplog):
    tree = {"a": np.arange(1000.0)}
    full = FullDisk(monkeypatch, tmp_path / "ck", full=3)
    with pytest.raises(RunError) as err:
        with C.Saver(tmp_path / "ck") as saver:
            for step in (1, 2, 3, 4):
                saver.save(step, {"a": tree["a"] + step})
    assert full.hits and "\n" not in str(err.value)
    assert str(err.value) == (f"{tmp_path / 'ck'}: the disk is full (no space left on device); the newest complete "
                              "checkpoint, step 2, is kept. Free some space and continue with --resume")
    assert sorted(p.name for p in (tmp_path / "ck").iterdir()) == ["1", "2"]    # no half-written step 3
    restored, step = C.restore(tmp_path / "ck", tree)
    assert step == 2 and float(restored["a"][5]) == 7.0
    out = capfd.readouterr()
    assert "Traceback" not in out.err + out.out and "Exception ignored" not in out.err
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR]          # orbax's reports are silenced
    # TensorStore's own report of it, as orbax raises it
    assert C.disk_full(ValueError('RESOURCE_EXHAUSTED: Error writing "00001/0.0" in OCDBT database at local file '
                                  '"/x/ckpt/2.orbax-checkpoint-tmp/": Failed to write 10436608 bytes to file 24: No '
                                  "space left on device [os_error_code='28']"))
    assert not C.disk_full(ValueError("OUT_OF_RANGE: Requested byte range [3, 9) is not valid for value of size 5"))


def test_a_run_that_fills_the_disk_stops_in_one_line_and_resumes(trainer, tmp_path, monkeypatch, capfd):
    """The save of iteration 2 finds the disk full: the run ends with one RunError naming the run and the step kept,
    leaves nothing half-written, and --resume, once there is space, continues from iteration 1 with its metrics."""
    run = tmp_path / "run"
    full = FullDisk(monkeypatch, run / "ckpt", full=2)
    with pytest.raises(RunError) as err:
        RUN.train(trainer, run, iterations=2, progress=False, save_every=0, log=lambda m: None)
    assert full.hits
    assert str(err.value).startswith(f"{run}: the disk is full") and "step 1, is kept" in str(err.value)
    assert sorted(p.name for p in (run / "ckpt").iterdir()) == ["1"]
    out = capfd.readouterr()
    assert "Traceback" not in out.err and "Exception ignored" not in out.err
    monkeypatch.undo()                                                   # space again
    messages = []
    summary = RUN.train(trainer, run, iterations=2, resume=True, progress=False, log=messages.append)
    assert "at iteration 1" in messages[0] and summary["iteration"] == 2 and summary["calls"] == 1
    assert C.steps(run / "ckpt") == [2, 1] and C.steps(run / "resume") == [2]
    assert [json.loads(r)["iteration"] for r in (run / "metrics.jsonl").read_text().splitlines()] == [1, 2]


def test_a_full_disk_while_writing_metrics_is_one_error(trainer, tmp_path, monkeypatch):
    """A metrics row that cannot be written (the disk filled up between two saves): one RunError, and the run's
    checkpoints are complete."""
    run = tmp_path / "run"
    real_open = open

    def full_open(path, mode="r", *args, **kwargs):
        if str(path) == str(run / "metrics.jsonl") and "a" in mode:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_open(path, mode, *args, **kwargs)
    monkeypatch.setattr("builtins.open", full_open)
    with pytest.raises(RunError, match=r"the disk is full .* step 1, is kept"):
        RUN.train(trainer, run, iterations=2, progress=False, save_every=0, log=lambda m: None)
    monkeypatch.undo()
    assert C.steps(run / "ckpt") == [1] and C.steps(run / "resume") == [1]


def test_a_resume_without_a_checkpoint_starts_afresh_and_says_so(trainer, tmp_path, monkeypatch):
    """Killed after its first metrics row and before its first checkpoint was complete: --resume says that it starts
    again from iteration 0 and drops that row."""
    run = tmp_path / "run"
    seen, fresh = {}, trainer.init()
    monkeypatch.setattr(trainer, "init", lambda key=None: fresh)                    # one first state for both runs
    monkeypatch.setattr(RUN, "chunk_build", lambda *args: None)                    # nothing is trained here
    monkeypatch.setattr(RUN, "_loop", lambda trainer, run, where, state, *rest: seen.update(state=state) or {})
    RUN.train(trainer, run, iterations=2, progress=False, log=lambda m: None)       # writes config.json
    (run / "metrics.jsonl").write_text(json.dumps({"iteration": 1}) + "\n")
    assert C.steps(run / "ckpt") == [] and C.steps(run / "resume") == []
    messages = []
    RUN.train(trainer, run, iterations=2, resume=True, progress=False, log=messages.append)
    assert [m for m in messages if "no checkpoint" in m] == [f"{run} holds no checkpoint yet: the run starts again "
                                                              "from iteration 0"]
    assert int(seen["state"].iteration) == 0 and (run / "metrics.jsonl").read_text() == ""


@pytest.mark.parametrize("save_every, rows_saved, kept", [(1e9, [3], [3]), (0.0, [1, 2, 3], [3, 2])])
def test_checkpoints_are_written_every_save_every_seconds_and_at_the_end(trainer, tmp_path, save_every, rows_saved,
                                                                           kept):
    """Metrics and the export after every call of one iteration; the checkpoints after the first call that comes
    `save_every` seconds after the last save (never, here, at 1e9 s: the last call alone) and at the end. The
    whole states keep the newest two steps, the compact one the newest."""
    run = tmp_path / "run"
    RUN.train(trainer, run, iterations=3, progress=False, log=lambda m: None, save_every=save_every)
    rows = [json.loads(r) for r in (run / "metrics.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [1, 2, 3]
    assert [r["iteration"] for r in rows if "ckpt_s" in r and "compact_s" in r] == rows_saved
    assert C.steps(run / "ckpt") == kept and C.steps(run / "resume") == [3]
    assert (run / "policy" / "policy.json").exists()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_first_signal_stops_the_run_after_its_chunk_with_a_checkpoint(trainer, tmp_path, sig):
    """A Ctrl-C (or a SIGTERM) while a chunk runs: that chunk ends, is saved, and the run stops (KeyboardInterrupt,
    as `dexguitar` reports it); --resume goes on from it. Sent here while the first call's export is judged, so the
    second call is the one that stops."""
    run, messages = tmp_path / "run", []

    def on_call(it):
        if it == 1:
            os.kill(os.getpid(), sig)
        return False
    before = signal.getsignal(sig)
    with pytest.raises(KeyboardInterrupt):
        RUN.train(trainer, run, iterations=5, progress=False, log=messages.append, save_every=1e9, on_call=on_call)
    name = signal.Signals(sig).name
    assert [m for m in messages if m.startswith(name)] == [
        f"{name}: stopping after this chunk with a checkpoint (Ctrl-C again stops at once)",
        f"{name}: stopped at iteration 2, saved (continue with --resume)"]
    assert signal.getsignal(sig) is before
    assert C.steps(run / "ckpt") == [2]
    assert [json.loads(r)["iteration"] for r in (run / "metrics.jsonl").read_text().splitlines()] == [1, 2]
    messages.clear()
    assert RUN.train(trainer, run, iterations=3, resume=True, progress=False, log=messages.append)["iteration"] == 3
    assert any(m.startswith(f"resumed {run} at iteration 2") for m in messages)


def test_a_background_save_holds_what_was_saved_while_a_donating_step_reuses_the_buffers(tmp_path):
    """The run's saves are written while the next chunk runs, and that chunk donates the state it was given: each
    step restores the values it was saved with, and an interruption (here Ctrl-C) still finishes the save in
    flight."""
    step = jax.jit(lambda t: jax.tree.map(lambda x: 2 * x + 1, t), donate_argnums=0)
    tree = {"a": jnp.arange(2**20, dtype=jnp.float32), "b": jnp.ones((3, 2))}
    with pytest.raises(KeyboardInterrupt):
        with C.Saver(tmp_path / "ck", keep=3) as saver:
            for i in (1, 2, 3):
                saver.save(i, tree)
                tree = step(tree)
            raise KeyboardInterrupt
    assert C.steps(tmp_path / "ck") == [3, 2, 1]
    template = {"a": jnp.zeros(2**20), "b": jnp.zeros((3, 2))}
    for i in (1, 2, 3):            # x after k steps of 2x + 1 is 2^k (x + 1) - 1
        restored, _ = C.restore(tmp_path / "ck", template, step=i)
        np.testing.assert_array_equal(restored["a"][:3], 2.0 ** (i - 1) * (np.arange(3) + 1) - 1)
        assert float(restored["a"][-1]) == 2.0 ** (i - 1) * 2**20 - 1
        np.testing.assert_array_equal(restored["b"], np.full((3, 2), 2.0 ** i - 1))


def test_a_process_killed_while_its_save_is_written_leaves_the_step_before_it(tmp_path):
    """SIGKILL while a background save is still being written (256 MiB): the step before is the newest and intact,
    and the half-written step is written again by the resumed run."""
    import subprocess
    import sys
    script = (
        "import os, signal, sys; import jax.numpy as jnp; from dexguitar.learn import checkpoint as C\n"
        "x = jnp.arange(2**26, dtype=jnp.float32)\n"
        "with C.Saver(sys.argv[1], keep=1) as saver:\n"
        "    saver.save(1, {'a': x}); saver.wait(); saver.save(2, {'a': x + 1}); os.kill(os.getpid(), signal.SIGKILL)\n")
    proc = subprocess.run([sys.executable, "-c", script, str(tmp_path / "ck")], capture_output=True)
    assert proc.returncode == -9
    assert C.steps(tmp_path / "ck") == [1]
    template = {"a": jnp.zeros(2**26)}
    restored, step = C.restore(tmp_path / "ck", template)
    assert step == 1 and float(restored["a"][12345]) == 12345.0 and float(restored["a"][-1]) == np.float32(2**26 - 1)
    C.save(tmp_path / "ck", 2, {"a": jnp.full(2**26, 5.0)}, keep=1)
    restored, step = C.restore(tmp_path / "ck", template)
    assert C.steps(tmp_path / "ck") == [2] and float(restored["a"][7]) == 5.0


def test_a_run_initialized_from_an_export_starts_from_its_weights(trainer, tmp_path, monkeypatch):
    """`--init-from`: the run's first state holds the export's policy and normalizer; the early check that the CLI
    makes before building anything reads policy.json only, so the weights are read once."""
    from dexguitar.learn import policy as PO
    RUN.train(trainer, tmp_path / "src", iterations=1, progress=False, log=lambda m: None)
    exported, _ = PO.load(tmp_path / "src" / "policy")
    fresh = jax.device_get(trainer.init().params["policy"])
    load, loads = PO.load, []
    monkeypatch.setattr(PO, "load", lambda d: loads.append(d) or load(d))
    assert RUN.check_init(tmp_path / "src", "left", 0)["hand"] == "left" and loads == []
    seen, messages = {}, []
    monkeypatch.setattr(RUN, "_loop", lambda trainer, run, where, state, *rest: seen.update(state=state) or {})
    RUN.train(trainer, tmp_path / "run", iterations=2, init_from=tmp_path / "src", progress=False,
              log=messages.append)
    assert len(loads) == 1 and any("policy initialized from" in m for m in messages)
    state = jax.device_get(seen["state"])
    for a, b in zip(jax.tree.leaves(state.params["policy"]), jax.tree.leaves(exported["policy"])):
        np.testing.assert_array_equal(np.asarray(a, np.float32), np.asarray(b))
    assert any(not np.array_equal(b, c) for b, c in zip(jax.tree.leaves(exported["policy"]), jax.tree.leaves(fresh)))
    np.testing.assert_array_equal(state.obs_norm["mean"], exported["obs_norm"]["mean"])


def test_a_run_resumes_on_another_machine_from_its_compact_state(trainer, tmp_path, monkeypatch):
    """`resume/` alone (what a device call brings back, without `ckpt/`) continues the run: networks, normalizers,
    key, iteration and the optimizers' scalars as saved; envs, replay buffers and Adam's moments fresh."""
    run = tmp_path / "run"
    RUN.train(trainer, run, iterations=2, progress=False, save_every=0, log=lambda m: None)
    rows = [json.loads(r) for r in (run / "metrics.jsonl").read_text().splitlines()]
    # each row times its two saves; the wall clock between two rows holds the first one's saves and the second's chunk
    assert all(r["ckpt_s"] > 0 and r["compact_s"] > 0 for r in rows)
    assert rows[1]["wall"] - rows[0]["wall"] >= rows[0]["ckpt_s"] + rows[0]["compact_s"] + rows[1]["seconds"]
    fresh = trainer.init()
    full, _ = C.restore(run / "ckpt", fresh)
    shutil.rmtree(run / "ckpt")                                        # it stays on the first machine
    assert C.steps(run / "resume") == [2]
    with pytest.raises(RunError, match="already holds a run"):
        RUN.check_out(run, resume=False)
    seen, messages = {}, []
    monkeypatch.setattr(RUN, "_loop", lambda trainer, run, where, state, *rest: seen.update(state=state) or {})
    RUN.train(trainer, run, iterations=3, resume=True, progress=False, log=messages.append)
    state = jax.device_get(seen["state"])
    assert any("at iteration 2 from its compact state" in m for m in messages) and int(state.iteration) == 2

    def same(a, b):
        return all(jax.tree.leaves(jax.tree.map(lambda x, y: np.array_equal(np.asarray(x), np.asarray(y)), a, b)))
    for name in RUN.KEPT:
        assert same(getattr(state, name), getattr(full, name)), name
    assert not same(full.params, fresh.params)                          # two iterations moved them
    assert same(state.env, fresh.env) and same(state.buffers, fresh.buffers)
    assert not same(full.opt, fresh.opt)                                # Adam did move
    adam = lambda x: isinstance(x, optax.ScaleByAdamState)             # noqa: E731
    adams = [jax.tree.leaves(x.opt, is_leaf=adam) for x in (state, fresh)]
    assert sum(map(adam, adams[0])) == 3                                # policy, critic, discriminators
    for got, new in zip(*adams):                                        # Adam restarts whole: moments and count
        assert not adam(got) or same(got, new)
    assert len(run.joinpath("metrics.jsonl").read_text().splitlines()) == 2


def test_the_compact_state_keeps_the_optimizers_scalars_and_restarts_adam(tmp_path):
    """An actor with a warm-up schedule and an adaptive rate: after 3 steps the schedule's count (3) and the rate
    (0.25) come back from `resume/`, Adam's count and moments come back fresh (0), the envs as the template has them."""
    from dexguitar.learn.trainer import TrainState
    opt_fn = optax.chain(optax.scale_by_adam(), optax.scale_by_schedule(lambda n: n))
    params = {"w": jnp.ones(3)}

    def state_of(opt, lr, env, it):
        return TrainState(params=params, opt={"policy": opt, "lr": jnp.float32(lr)}, obs_norm={}, disc_norm={},
                          popart={}, buffers={}, env=env, key=jax.random.PRNGKey(0), iteration=jnp.int32(it))
    opt = opt_fn.init(params)
    for _ in range(3):
        _, opt = opt_fn.update({"w": jnp.full(3, 2.0)}, opt)
    C.save(tmp_path, 3, state_of(opt, 0.25, jnp.full(4, 7.0), 3), keep=1, only=RUN.compact)
    template = state_of(opt_fn.init(params), 1.0, jnp.zeros(4), 0)
    got, step = C.restore(tmp_path, template, only=RUN.compact)
    got = got.replace(opt=RUN.restart_adam(got.opt, template.opt))
    adam, schedule = got.opt["policy"]
    assert step == 3 and int(got.iteration) == 3 and float(got.opt["lr"]) == 0.25 and int(schedule.count) == 3
    assert int(adam.count) == 0 and not np.any(adam.mu["w"]) and not np.any(adam.nu["w"])
    assert not np.any(got.env)                                          # rebuilt, not carried


def test_a_run_directory_in_use_is_refused(tmp_path):
    held = RUN.RunDir(tmp_path / "run")
    with pytest.raises(RunError, match="in use by process"):
        RUN.RunDir(tmp_path / "run")
    held.close()
    RUN.RunDir(tmp_path / "run").close()                                  # free again once released


def test_metrics_rows_past_the_checkpoint_are_dropped_on_resume(tmp_path):
    run = RUN.RunDir(tmp_path / "run")
    run.metrics.write_text("".join(json.dumps({"iteration": i}) + "\n" for i in (1, 2, 3)) + '{"itera')
    run.truncate_metrics(2)                                               # killed after row 3, before its save
    assert [json.loads(r)["iteration"] for r in run.metrics.read_text().splitlines()] == [1, 2]
    run.close()


def test_resume_with_another_setup_names_the_differences(tmp_path):
    run = RUN.RunDir(tmp_path / "run")
    record = {"train": {"hand": "left", "num_envs": 4, "iterations": 2}, "env": {"shift_prob": 0.5},
              "songs": ["a"]}
    with pytest.raises(RunError, match="no run to resume"):
        run.check_resume(record)
    run.config.write_text(json.dumps(record))
    run.check_resume(json.loads(json.dumps(dict(record, train=dict(record["train"], iterations=9)))))  # may grow
    other = dict(record, train=dict(record["train"], hand="right", num_envs=8), songs=["b"])
    with pytest.raises(RunError) as err:
        run.check_resume(other)
    msg = str(err.value)
    assert "train.hand: 'left' -> 'right'" in msg and "train.num_envs: 4 -> 8" in msg and "songs" in msg
    # a run recorded before a field existed resumes when the field keeps its default, and not otherwise
    run.check_resume(dict(record, train=dict(record["train"], kl_target=0.0)))
    with pytest.raises(RunError, match="train.clip: 0.2 -> 0.3"):
        run.check_resume(dict(record, train=dict(record["train"], clip=0.3)))
    run.close()


# ---------------------------------------------------------------------------------------------- the command line

BAD = [
    ["song", "info", "{tmp}/missing.json"],
    ["song", "convert", "ode_to_joy", "{tmp}/no/such/dir/x.json"],
    ["song", "convert", "ode_to_joy", "{tmp}/x.txt"],
    ["train", "--song", "{tmp}/empty", "--out", "{tmp}/r1", "--config", "cpu_smoke"],
    ["train", "--song", "{tmp}/mistyped.json", "--out", "{tmp}/r2", "--config", "cpu_smoke"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r3", "--config", "{tmp}/missing.py"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r4", "--config", "{tmp}/noconfig.py"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r5", "--config", "cpu_smoke", "--resume"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/afile", "--config", "cpu_smoke"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r6", "--config", "cpu_smoke",
     "--motion", "{tmp}/motion.npz"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r7", "--config", "cpu_smoke",
     "--init-from", "{tmp}/nothing"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r8", "--config", "{tmp}/residual.py",   # a plain policy as
     "--init-from", "models/policies/left_ode_to_joy"],                                     # a residual's start
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r9", "--config", "no_such_config"],
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r10", "--config", "experiments/cpu_smoke.py"],   # moved
    ["train", "--song", "ode_to_joy", "--out", "{tmp}/r11", "--config", "cpu_smoke", "--set", "num_envz=4"],
    ["sync", "--song", "ode_to_joy", "--out", "{tmp}/s3", "--config", "cpu_smoke", "--set", "env.hold_reward=lots"],
    ["eval", "--ckpt", "{tmp}/nothing", "--song", "ode_to_joy"],
    ["sync", "--song", "ode_to_joy", "--left", "{tmp}/nothing", "--right", "{tmp}/nothing", "--out", "{tmp}/s1"],
    ["songs", "{tmp}/missing.json", "--out", "{tmp}/s2"],
    ["play", "--ckpt", "{tmp}/nothing", "--song", "ode_to_joy", "--out", "{tmp}/p"],
    ["play", "--left", "models/policies/left_ode_to_joy", "--right", "models/policies/right_mixed", "--song",
     "{tmp}/missing.gp5", "--out", "{tmp}/p"],
    ["plot", "{tmp}/nothing", "--out", "{tmp}/p.png"],
    ["motion", "info", "{tmp}/motion.npz"],
]


@pytest.mark.parametrize("argv", BAD, ids=[" ".join(a[:2]) + f" #{i}" for i, a in enumerate(BAD)])
def test_every_command_refuses_bad_paths_in_one_line(argv, tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    (tmp_path / "noconfig.py").write_text("X = 1\n")
    (tmp_path / "afile").write_text("not a directory\n")
    (tmp_path / "residual.py").write_text("from dexguitar.configs.cpu_smoke import CONFIG\n"
                                          "from dexguitar.envs import EnvConfig\n"
                                          "ENV = EnvConfig(feedforward=True)\n")
    (tmp_path / "motion.npz").write_bytes(b"PK\x03\x04 truncated")
    argv = [a.format(tmp=tmp_path) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    assert "Traceback" not in err[0]


@pytest.mark.parametrize("argv", [["train", "--envs", "0"], ["train", "--iterations", "-1"],
                                  ["train", "--max-minutes", "0"], ["sync", "--save-every", "-1"]])
def test_impossible_numbers_are_refused_by_the_parser(argv, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(argv + ["--out", "x"])
    assert exit_.value.code == 2 and "must be" in capsys.readouterr().err


def test_sync_and_play_without_policies_take_the_general_pair(tmp_path, monkeypatch, capsys):
    from dexguitar import cli
    from dexguitar.planner import PLANNER_VERSION, RIGHT_PLANNER_VERSION
    assert cli._general_pair("sync") == (str(cli.POLICIES / "left_general"), str(cli.POLICIES / "right_mixed"))
    assert cli._general_pair("play") == (str(cli.POLICIES / "left_general"), str(cli.POLICIES / "right_general"))
    meta = json.loads((cli.POLICIES / "left_general" / "policy.json").read_text())
    assert meta["hand"] == "left" and meta["feedforward"] == PLANNER_VERSION        # a residual on the planner
    meta = json.loads((cli.POLICIES / "right_general" / "policy.json").read_text())
    assert meta["hand"] == "right" and meta["right_feedforward"] == RIGHT_PLANNER_VERSION
    monkeypatch.setitem(cli.GENERAL, "left", tmp_path / "none")          # a checkout without it
    for argv in (["sync", "--song", "ode_to_joy", "--out", str(tmp_path / "s")],
                 ["play", "--song", "ode_to_joy", "--out", str(tmp_path / "p")]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "no general left hand" in err[0] and "--left and --right" in err[0], err


def test_play_takes_the_songs_gsync_synchronizer_where_one_is_shipped(tmp_path, monkeypatch):
    from dexguitar import cli
    monkeypatch.setattr(cli, "POLICIES", tmp_path)
    assert cli.gsync_for("../notes/wipe_out.json") is None
    (tmp_path / "gsync_wipe_out").mkdir()
    (tmp_path / "gsync_wipe_out" / "policy.json").write_text("{}")
    assert cli.gsync_for("../notes/wipe_out.json") == tmp_path / "gsync_wipe_out"
    assert cli.gsync_for("wipe_out") == tmp_path / "gsync_wipe_out"          # an embedded song's name
    assert cli.gsync_for("snow.gp5") is None
