"""The left hand as a residual on the planner (`EnvConfig(feedforward=True)`, `planner/plans.py`): a zero residual
must play exactly as the scripted player does, and a training window must start in its planned state and read the
plan frame by frame, or the feedforward belongs to other notes than the ones being played."""
import json
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
from dexguitar.errors import UserError
from dexguitar.learn import policy as PO
from dexguitar.planner import plans as FF
from dexguitar import planner as PL
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


def one_song_at_a_time(monkeypatch, params, spec, limit: str, song):
    """`song` evaluated twice in one call and once alone, with the CPU's songs per program (`limit`) set to 1:
    (two, one). Both calls take the one-song program and each copy scores exactly as the song alone."""
    from dexguitar.perform import evaluate as EV
    monkeypatch.setattr(EV, limit, 1)
    monkeypatch.setattr(EV, "_CACHE", {})
    two = EV.evaluate(params, spec, [song, song])
    one = EV.evaluate(params, spec, [song])
    assert len(EV._CACHE) == 1                                  # a single program, of one song's shape
    assert list(two) == [song.title, f"{song.title} (1)"] and list(one) == [song.title]
    assert two[song.title] == one[song.title] == two[f"{song.title} (1)"]
    return two, one


def zero_residual(env, hand: str = "left") -> tuple[dict, PO.PolicySpec]:
    spec = PO.PolicySpec("policy", hand, env.action_size, env.layout, feedforward=hand == "left",
                         right_feedforward=hand == "right")
    params = PO.template(spec)
    params["obs_norm"]["var"] = np.ones_like(params["obs_norm"]["var"])
    return params, spec


def test_zero_residual_plays_as_the_scripted_player(plans, monkeypatch):
    """Also: a CPU plays one hand `CPU_HAND_SONGS` songs at a time (48 left-hand songs in one program stalled XLA's
    CPU run on a 2-core machine). Here one at a time: two songs take the one-song program and each copy scores
    exactly as the song alone."""
    config = envs.EnvConfig().evaluation()
    scripted = ScriptedPlayer(envs.make("left", plans, config)).play(0)["left"]
    env = envs.make("left", plans, config)
    params, spec = zero_residual(env.env)
    _, one = one_song_at_a_time(monkeypatch, params, spec, "CPU_HAND_SONGS", melody())
    played = one["scripted test melody"]
    assert played["summary"]["left"]["notes"] == sum(fret > 0 for _, fret in MELODY)     # open strings: no press
    assert played["summary"]["left"]["f1"] == pytest.approx(scripted["f1"], abs=1e-6)
    assert scripted["f1"] >= 0.95


def test_right_zero_residual_plays_as_the_scripted_player(plans):
    """The right hand on its planner's feedforward (`EnvConfig.right_feedforward`), on 8-frame string crossings that
    `right_mixed` misses."""
    song = fast_lines()
    config = envs.EnvConfig().evaluation()
    scripted = ScriptedPlayer(envs.make("right", [TL.from_song(song)], config)).play(0)["right"]
    params, spec = zero_residual(envs.make("right", [TL.from_song(song)], config).env, "right")
    assert spec.env_config(config).right_feedforward is True and not spec.env_config(config).feedforward
    played = evaluate(params, spec, [song])["fast lines"]["summary"]["right"]
    assert played["notes"] == len(song.notes)
    assert played["f1"] == pytest.approx(scripted["f1"], abs=1e-6)
    assert scripted["f1"] >= 0.95


@pytest.mark.parametrize("hand", ["left", "right"])
def test_window_starts_in_its_planned_state_and_reads_one_frame_per_step(plans, hand):
    ff = {"feedforward": True} if hand == "left" else {"right_feedforward": True}
    config = envs.EnvConfig(shift_prob=0.0, tempo_prob=0.0, **ff)
    env = envs.make(hand, plans, config)
    core = env.env.env                                  # AutoReset(ChainWindows(LeftEnv))
    assert core.planned and list(core.plans) == [hand]
    plan = core.songs.plan if hand == "left" else core.songs.plan_right
    assert (core.songs.plan is None) == (hand == "right")        # only the plan the config asks for is made
    j = np.asarray(core.hands[0].qpos)
    # the core env's reset and step (the wrappers' episode rules: tests/test_envs.py), a smaller program to compile
    reset, step, feedforward = jax.jit(core.reset), jax.jit(core.step), jax.jit(core.feedforward)
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
            if bool(state.cursor.over):
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
    FF.attach(TL.stack(plans), hand="right")                             # another planner: another plan
    out, err = capsys.readouterr()
    assert len(list(tmp_path.glob("*.npz"))) == 2
    assert out == "" and err.startswith("planned the right hand for 1 song (")    # on stderr: `eval --json` prints
    assert err.rstrip().endswith(" on 1 process")                                # only JSON on stdout
    np.testing.assert_array_equal(np.asarray(first.plan.action), np.asarray(again.plan.action))
    assert first.plan.action.shape[1] >= FF.MIN_FRAMES and int(first.plan.frames[0]) > 0
    assert np.all(np.abs(np.asarray(first.plan.action)) <= 1.0)
    # a plan made with other planner constants is not reused: the key holds them
    notes = FF.song_notes(TL.stack(plans), 0, 5)
    keys = {hand: FF._job_key(notes.left, notes.onset, hand, notes.pick) for hand in ("left", "right")}
    duet = FF._job_key(notes.left, notes.onset, "right", notes.pick, after=True)
    assert len({*keys.values(), duet}) == 3
    monkeypatch.setattr(PL.ScriptedLeft, "open_clear", PL.ScriptedLeft.open_clear + 0.001)
    assert FF._job_key(notes.left, notes.onset) != keys["left"]
    assert FF._job_key(notes.left, notes.onset, "right", notes.pick) == keys["right"]
    assert FF._job_key(notes.left, notes.onset, "right", notes.pick, after=True) != duet    # it waits for the left
    monkeypatch.setattr(PL.ScriptedRight, "early_gap", PL.ScriptedRight.early_gap + 0.5)
    assert FF._job_key(notes.left, notes.onset, "right", notes.pick) != keys["right"]


def test_plans_are_made_with_one_blas_thread_even_for_one_song(monkeypatch):
    """Planning never runs in the calling process (whose BLAS keeps the threads it started with): even a single job
    goes to a worker started with one BLAS thread, so that one process per core does the work."""
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    out, used = FF.in_processes(os.getenv, ["OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"], workers=1)
    assert out == ["1", "1"] and used == 1
    assert os.environ["OPENBLAS_NUM_THREADS"] == "2"                         # the caller's own setting is back


def worker_pid(_) -> int:
    return os.getpid()


def test_a_kept_pool_plans_the_next_songs_in_the_same_workers_and_leaves_with_its_parent(tmp_path):
    """Planning reuses its worker processes between calls (a fresh worker costs seconds of imports and planner
    set-up); a kept worker that died is replaced; the workers of a process that leaves without shutting them down
    (`os._exit`, a kill) leave too."""
    first, _ = FF.in_processes(worker_pid, [None], workers=1, keep=True)
    again, _ = FF.in_processes(worker_pid, [None], workers=1, keep=True)
    fresh, _ = FF.in_processes(worker_pid, [None], workers=1)
    assert first == again and fresh != first and os.getpid() not in first + fresh
    os.kill(first[0], signal.SIGKILL)                     # a kept worker that dies while it waits is replaced
    time.sleep(1.5)
    replaced, _ = FF.in_processes(worker_pid, [None], workers=1, keep=True)
    assert replaced != first
    script = tmp_path / "leave.py"
    script.write_text("import os\nfrom dexguitar.planner import plans as FF\n"
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
    assert again.feedforward is True is again.env_config(envs.EnvConfig()).feedforward
    assert spec.to_meta()["feedforward"] == PL.PLANNER_VERSION == 21            # what older releases read
    plain = PO.PolicySpec("policy", "left", env.action_size, env.layout)
    assert "feedforward" not in plain.to_meta() and not PO.PolicySpec.from_meta(plain.to_meta()).feedforward
    with pytest.raises(ValueError, match="no left hand"):
        envs.make("right", [TL.from_song(melody())], envs.EnvConfig(feedforward=True))
    made = envs.make("left", [TL.from_song(melody())], envs.EnvConfig(feedforward=True))     # the env plans the song
    np.testing.assert_array_equal(made.env.env.songs.plan.action,
                                  FF.attach(TL.batch([TL.from_song(melody())])).plan.action)
    right = envs.make("right", [TL.from_song(melody())], envs.EnvConfig())
    _, rspec = zero_residual(right.env, "right")
    again = PO.PolicySpec.from_meta(rspec.to_meta())
    assert again.right_feedforward is True and not again.feedforward
    assert rspec.to_meta()["right_feedforward"] == PL.RIGHT_PLANNER_VERSION == 4
    assert again.env_config(envs.EnvConfig(feedforward=True)) == envs.EnvConfig(right_feedforward=True)
    assert "right_feedforward" not in spec.to_meta()
    with pytest.raises(ValueError, match="no right hand"):
        envs.make("left", [TL.from_song(melody())], envs.EnvConfig(right_feedforward=True))
    made = envs.make("right", [TL.from_song(melody())], envs.EnvConfig(right_feedforward=True))
    np.testing.assert_array_equal(made.env.env.songs.plan_right.action,
                                  FF.attach(TL.batch([TL.from_song(melody())]), hand="right").plan_right.action)


def test_a_policy_on_a_planner_version_this_release_no_longer_has_is_refused(tmp_path):
    """`policy.json` holds the planner's version number: 21 (left) and 4 (right) load as residuals on the planner;
    any other (true was version 1) is refused in one line naming the file, which asks for a newer export."""
    from dexguitar.cli import POLICIES
    env = envs.make("left", [TL.from_song(melody())], envs.EnvConfig())
    meta = zero_residual(env.env)[1].to_meta()
    right = zero_residual(envs.make("right", [TL.from_song(melody())], envs.EnvConfig()).env, "right")[1].to_meta()
    for name, m in (("left21", dict(meta, feedforward=21)), ("right4", dict(right, right_feedforward=4)),
                    ("plain", {k: v for k, v in meta.items() if k != "feedforward"})):
        (tmp_path / name).mkdir()
        (tmp_path / name / "policy.json").write_text(json.dumps(m))
        spec = PO.PolicySpec.from_meta(PO.read_meta(tmp_path / name))
        assert (spec.feedforward, spec.right_feedforward) == {"left21": (True, False), "right4": (False, True),
                                                              "plain": (False, False)}[name]
    for name, m in (("left9", dict(meta, feedforward=9)), ("left_true", dict(meta, feedforward=True)),
                    ("right3", dict(right, right_feedforward=3))):
        (tmp_path / name).mkdir()
        path = tmp_path / name / "policy.json"
        path.write_text(json.dumps(m))
        with pytest.raises(UserError) as err:
            PO.read_meta(tmp_path / name)
        message = str(err.value)
        assert message.startswith(f"{path}: ") and "\n" not in message
        assert "trained on a planner version this release no longer has" in message
        assert "only the left planner of version 21 and the right planner of version 4" in message
        assert "newer export" in message
    assert '("feedforward": 9)' in str(pytest.raises(UserError, PO.read_meta, tmp_path / "left9").value)
    # the shipped residuals: left on version 21, right on version 4, a synchronizer of a left one on 21
    for name, flags in (("left_general", (True, False)), ("right_general", (False, True)),
                        ("gsync_snow", (True, False))):
        spec = PO.PolicySpec.from_meta(PO.read_meta(POLICIES / name))
        assert (spec.feedforward, spec.right_feedforward) == flags, name


def test_a_run_recorded_with_the_planner_version_resumes_on_the_planner():
    """A run's config.json may hold the planner's version number as `env.feedforward` (21) or
    `env.right_feedforward` (4): resumed, it trains on the planner; a run on another version cannot go on."""
    from dexguitar.errors import RunError
    from dexguitar.learn.run import planner_flags
    recorded = {"feedforward": 21, "right_feedforward": 4, "mirror": False}
    assert planner_flags(recorded) == {"feedforward": True, "right_feedforward": True, "mirror": False}
    assert planner_flags({"feedforward": True, "right_feedforward": 0}) == {"feedforward": True,
                                                                             "right_feedforward": False}
    with pytest.raises(RunError, match="run/config.json: made on a planner version this release no longer has"):
        planner_flags({"feedforward": 9}, "run/config.json")
