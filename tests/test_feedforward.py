"""The left hand as a residual on the planner (`EnvConfig(feedforward=FF.LATEST)`, `motion/feedforward.py`): a zero residual
must play exactly as the scripted player does, and a training window must start in its planned state and read the
plan frame by frame, or the feedforward belongs to other notes than the ones being played."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar import envs
from dexguitar.learn import policy as PO
from dexguitar.motion import feedforward as FF
from dexguitar.motion.planner import RIGHT_LATEST
from dexguitar.perform.scripted import ScriptedPlayer
from dexguitar.music import cursor as CU
from dexguitar.music import timeline as TL
from dexguitar.perform.evaluate import evaluate
from test_scripted import MELODY, fast_lines, melody


@pytest.fixture(scope="module")
def plans(tmp_path_factory, monkeypatch_module):
    monkeypatch_module.setenv("DEXGUITAR_PLANS", str(tmp_path_factory.mktemp("plans")))
    return [TL.from_song(melody())]


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as mp:
        yield mp


def zero_residual(env, hand: str = "left") -> tuple[dict, PO.PolicySpec]:
    spec = PO.PolicySpec("policy", hand, env.action_size, env.layout, feedforward=FF.LATEST if hand == "left" else 0,
                         right_feedforward=RIGHT_LATEST if hand == "right" else 0)
    params = PO.template(spec)
    params["obs_norm"]["var"] = np.ones_like(params["obs_norm"]["var"])
    return params, spec


def test_zero_residual_plays_as_the_scripted_player(plans):
    config = envs.EnvConfig().evaluation()
    scripted = ScriptedPlayer(envs.make("left", plans, config)).play(0)["left"]
    env = envs.make("left", plans, config)
    params, spec = zero_residual(env.env)
    played = evaluate(params, spec, [melody()])["scripted test melody"]
    assert played["summary"]["left"]["notes"] == sum(fret > 0 for _, fret in MELODY)     # open strings: no press
    assert played["summary"]["left"]["f1"] == pytest.approx(scripted["f1"], abs=1e-6)
    assert scripted["f1"] >= 0.95


def test_right_zero_residual_plays_as_the_scripted_player(plans):
    """The right hand on its planner's feedforward (`EnvConfig.right_feedforward`), on 8-frame string crossings that
    `right_mixed` and version 1 of the planner miss."""
    song = fast_lines()
    config = envs.EnvConfig().evaluation()
    scripted = ScriptedPlayer(envs.make("right", [TL.from_song(song)], config)).play(0)["right"]
    params, spec = zero_residual(envs.make("right", [TL.from_song(song)], config).env, "right")
    assert spec.env_config(config).right_feedforward == RIGHT_LATEST and not spec.env_config(config).feedforward
    played = evaluate(params, spec, [song])["fast lines"]["summary"]["right"]
    assert played["notes"] == len(song.notes)
    assert played["f1"] == pytest.approx(scripted["f1"], abs=1e-6)
    assert scripted["f1"] >= 0.95


@pytest.mark.parametrize("hand", ["left", "right"])
def test_window_starts_in_its_planned_state_and_reads_one_frame_per_step(plans, hand):
    ff = {"feedforward": FF.LATEST} if hand == "left" else {"right_feedforward": RIGHT_LATEST}
    config = envs.EnvConfig(shift_prob=0.0, tempo_prob=0.0, **ff)
    env = envs.make(hand, FF.prepare(plans, config), config)
    core = env.env.env                                  # AutoReset(ChainWindows(LeftEnv))
    assert core.planned and list(core.plans) == [hand]
    plan = core.songs.plan if hand == "left" else core.songs.plan_right
    assert (core.songs.plan is None) == (hand == "right")        # only the plan the config asks for is made
    j = np.asarray(core.hands[0].qpos)
    reset, step, feedforward = jax.jit(env.reset), jax.jit(env.step), jax.jit(core.feedforward)
    for seed in range(3):
        state = reset(jax.random.PRNGKey(seed))
        window = state.cursor.window
        start = int(window.start)
        # row 0 is the rest before note `first`, which the plan (a grace rest, then the song) starts at its onset +
        # rest_frames: so the window starts at the note's onset
        assert start == int(core.songs.onset[0][int(window.first)])
        np.testing.assert_allclose(np.asarray(state.body.data.qpos)[j], np.asarray(plan.qpos[0, start]), atol=1e-6)
        ff = np.asarray(feedforward(state.cursor))
        np.testing.assert_array_equal(ff, np.asarray(plan.action[0, start]))
        for k in range(1, 4):
            state = step(state, jnp.zeros(env.action_size))
            if bool(state.done):
                break
            assert int(CU.song_frame(state.cursor)) == start + k
            np.testing.assert_array_equal(np.asarray(feedforward(state.cursor)),
                                          np.asarray(plan.action[0, start + k]))


def test_plans_come_from_the_disk_cache_the_second_time(plans, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DEXGUITAR_PLANS", str(tmp_path))
    made = []
    first = FF.attach(TL.stack(plans), log=made.append)
    assert len(made) == 1 and len(list(tmp_path.glob("*.npz"))) == 1
    again = FF.attach(TL.stack(plans), log=made.append)
    assert len(made) == 1                               # the second time: read, not planned
    capsys.readouterr()
    FF.attach(TL.stack(plans), version=1)                                # another planner: another plan
    out, err = capsys.readouterr()
    assert len(list(tmp_path.glob("*.npz"))) == 2
    assert out == "" and err.startswith("planned the left hand for 1 song (")     # on stderr: `eval --json` prints
    assert err.rstrip().endswith(" on 1 process")                                # only JSON on stdout
    np.testing.assert_array_equal(np.asarray(first.plan.action), np.asarray(again.plan.action))
    assert first.plan.action.shape[1] >= FF.MIN_FRAMES and int(first.plan.frames[0]) > 0
    assert np.all(np.abs(np.asarray(first.plan.action)) <= 1.0)


def test_plans_are_made_with_one_blas_thread_even_for_one_song(monkeypatch):
    """A plan depends on the BLAS thread count, so planning never runs in the calling process (whose BLAS keeps the
    threads it started with): even a single job goes to a worker started with one thread."""
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    out, used = FF.in_processes(os.getenv, ["OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"], workers=1)
    assert out == ["1", "1"] and used == 1
    assert os.environ["OPENBLAS_NUM_THREADS"] == "2"                         # the caller's own setting is back


def worker_pid(_) -> int:
    return os.getpid()


def test_a_kept_pool_plans_the_next_songs_in_the_same_workers_and_leaves_with_its_parent(tmp_path):
    """Planning reuses its worker processes between calls (a fresh worker costs seconds of imports and planner
    set-up), except for the left planner before version 5, whose plans depend on what its worker solved before; a
    kept worker that died is replaced; the workers of a process that leaves without shutting them down (`os._exit`, a
    kill) leave too."""
    first, _ = FF.in_processes(worker_pid, [None], workers=1, keep=True)
    again, _ = FF.in_processes(worker_pid, [None], workers=1, keep=True)
    fresh, _ = FF.in_processes(worker_pid, [None], workers=1)
    assert first == again and fresh != first and os.getpid() not in first + fresh
    os.kill(first[0], signal.SIGKILL)                     # a kept worker that dies while it waits is replaced
    time.sleep(1.5)
    replaced, _ = FF.in_processes(worker_pid, [None], workers=1, keep=True)
    assert replaced != first
    assert FF._reusable((None, None, None, 5)) and not FF._reusable((None, None, None, 4))
    assert FF._reusable((None, None, None, 4, "right")) and not FF._reusable((None, None, None, 4, "left", None))
    script = tmp_path / "leave.py"
    script.write_text("import os\nfrom dexguitar.motion import feedforward as FF\n"
                      "def pid(_):\n    return os.getpid()\n"
                      "if __name__ == '__main__':\n"
                      "    print(FF.in_processes(pid, [None], workers=1, keep=True)[0][0], flush=True)\n"
                      "    os._exit(0)\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120,
                          cwd=Path(__file__).resolve().parents[1])
    worker = int(done.stdout.split()[-1])
    deadline = time.time() + 20
    while time.time() < deadline and Path(f"/proc/{worker}").exists():
        time.sleep(0.5)
    assert not Path(f"/proc/{worker}").exists() or "zombie" in Path(f"/proc/{worker}/status").read_text().lower()


def test_the_residual_flag_travels_with_the_policy():
    env = envs.make("left", [TL.from_song(melody())], envs.EnvConfig())
    _, spec = zero_residual(env.env)
    again = PO.PolicySpec.from_meta(spec.to_meta())
    assert again.feedforward == FF.LATEST == again.env_config(envs.EnvConfig()).feedforward
    legacy = dict(spec.to_meta(), feedforward=True)                   # the first residuals: planner version 1
    assert PO.PolicySpec.from_meta(legacy).feedforward == 1
    plain = PO.PolicySpec("policy", "left", env.action_size, env.layout)
    assert "feedforward" not in plain.to_meta() and not PO.PolicySpec.from_meta(plain.to_meta()).feedforward
    with pytest.raises(ValueError, match="no left hand"):
        envs.make("right", [TL.from_song(melody())], envs.EnvConfig(feedforward=True))
    with pytest.raises(ValueError, match="feedforward.prepare"):        # plans are not made behind the env's back
        envs.make("left", [TL.from_song(melody())], envs.EnvConfig(feedforward=True))
    right = envs.make("right", [TL.from_song(melody())], envs.EnvConfig())
    _, rspec = zero_residual(right.env, "right")
    again = PO.PolicySpec.from_meta(rspec.to_meta())
    assert again.right_feedforward == RIGHT_LATEST and not again.feedforward
    assert again.env_config(envs.EnvConfig(feedforward=FF.LATEST)) == envs.EnvConfig(right_feedforward=RIGHT_LATEST)
    assert "right_feedforward" not in spec.to_meta()
    with pytest.raises(ValueError, match="no right hand"):
        envs.make("left", [TL.from_song(melody())], envs.EnvConfig(right_feedforward=RIGHT_LATEST))
    with pytest.raises(ValueError, match="feedforward.prepare"):
        envs.make("right", [TL.from_song(melody())], envs.EnvConfig(right_feedforward=RIGHT_LATEST))
