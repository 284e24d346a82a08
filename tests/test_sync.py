"""The synchronizer (Sec. 4, Eq. 1-2): unchanged actions at initialization, frozen policies, one training iteration in
the duet env, exact resume, the export and the `dexguitar sync` / `eval` commands on a tiny song."""
import json

import chex
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dexguitar.envs.layout import ObsLayout
from dexguitar.errors import UserError
from dexguitar.learn import checkpoint as C
from dexguitar.learn import networks as N
from dexguitar.learn import policy as PO
from dexguitar.learn import sync as SY

HISTORY = 2
DUET = ObsLayout(("left", "right"), HISTORY, 208, 35, 6)      # 2 frames x 16 links x 13, 5 notes x 7 per hand
SPEC = PO.PolicySpec("synchronizer", "duet", 54, DUET)

TINY_SONG = """title: two notes and a chord
tempo: 120
grid: 1/8
e|--0---------|
B|----1-------|
G|------0-----|
D|------2-----|
A|------3-----|
E|------------|
"""


def random_policy(key, meta_hand, noise=0.05):
    """An exported-looking single-hand policy with random weights and a non-trivial normalizer. With noise > 0 the
    weights are larger than at init, so that the latent matters for the action (but the hands flail)."""
    k1, k2, k3, k4 = jax.random.split(key, 4)
    policy = N.Policy(27)
    params = N.init_params(policy, k1, (HISTORY, 208), (35,))
    # larger random weights than the init, so that the latent matters for the action
    params = jax.tree.map(lambda x: x + noise * jax.random.normal(k4, x.shape), params)
    norm = {"mean": jax.random.normal(k2, (208,)), "var": jnp.exp(jax.random.normal(k3, (208,))),
            "count": jnp.float32(100.0)}
    meta = {"hand": meta_hand, "action_size": 27, "goal_size": 35, "obs_size": 2 * 208 + 35, "samples": 0}
    return {"policy": params, "obs_norm": norm}, meta


@pytest.fixture(scope="module")
def pair():
    return random_policy(jax.random.PRNGKey(1), "left"), random_policy(jax.random.PRNGKey(2), "right")


def test_synchronizer_at_initialization_leaves_both_policies_actions_unchanged(pair):
    (left, _), (right, _) = pair
    sync, norm = PO.init_synchronizer(jax.random.PRNGKey(3), left, right, DUET)
    params = {"policy": sync, "obs_norm": norm, "frozen": {"left": left, "right": right}}
    obs = jax.random.normal(jax.random.PRNGKey(4), (7, 2 * 416 + 70))
    # each policy alone on its own part of the duet observation, cut by hand: frame t holds [left 208 | right 208]
    frames = obs[:, :832].reshape(7, HISTORY, 2, 208)
    alone = []
    for i, (p, goal) in enumerate(((left, obs[:, 832:867]), (right, obs[:, 867:902]))):
        alone.append(N.Policy(27).apply(p["policy"], N.normalize(p["obs_norm"], frames[:, :, i]), goal))
    mu, log_std = PO.distribution(SPEC, params, obs)
    np.testing.assert_allclose(mu, jnp.concatenate([alone[0][0], alone[1][0]], -1), atol=1e-6)
    np.testing.assert_allclose(log_std, jnp.concatenate([alone[0][1], alone[1][1]], -1), atol=1e-6)
    # the layout's own cut agrees with the one by hand
    np.testing.assert_array_equal(DUET.hand_obs(obs, 1), jnp.concatenate([frames[:, :, 1].reshape(7, -1),
                                                                          obs[:, 867:902]], -1))
    # the encoders are copies of the policies' and the offsets are zero ...
    assert jax.tree.all(jax.tree.map(np.array_equal, sync["params"]["encoder_left"],
                                     left["policy"]["params"]["encoder"]))
    dz = N.Synchronizer().apply(sync, jnp.zeros((HISTORY, 208)), jnp.zeros(35), jnp.ones((HISTORY, 208)),
                                jnp.ones(35))
    assert float(jnp.abs(jnp.concatenate(dz)).max()) == 0.0
    # ... and a non-zero last layer does move both hands (the check above could fail) ...
    moved = jax.tree.map(lambda x: x, sync)
    moved["params"]["dz"]["bias"] = jnp.ones(512)
    mu2, _ = PO.distribution(SPEC, {**params, "policy": moved}, obs)
    assert float(jnp.abs(mu2[:, :27] - mu[:, :27]).max()) > 1e-3
    assert float(jnp.abs(mu2[:, 27:] - mu[:, 27:]).max()) > 1e-3
    # ... unless it is the "before" player, which zeroes that layer
    mu3, _ = PO.distribution(SPEC, PO.unsynchronized({**params, "policy": moved}), obs)
    np.testing.assert_array_equal(mu3, mu)


def test_a_scaled_left_hand_acts_at_its_scale_alone_and_in_the_duet(pair, tmp_path):
    from dexguitar.learn.run import check_init
    (left, lmeta), (right, _) = pair
    one = PO.PolicySpec("policy", "left", 27, DUET.one_hand(0), feedforward=True)
    scaled = PO.PolicySpec("policy", "left", 27, DUET.one_hand(0), feedforward=True, scale=0.01)
    obs = jax.random.normal(jax.random.PRNGKey(5), (3, 451))
    mu, log_std = PO.distribution(one, left, obs)
    mu_s, log_std_s = PO.distribution(scaled, left, obs)
    np.testing.assert_allclose(mu_s, 0.01 * mu, rtol=1e-5, atol=1e-9)          # mean and std: a hundredth
    np.testing.assert_allclose(log_std_s, log_std + np.log(0.01), atol=1e-5)
    assert PO.PolicySpec.from_meta(scaled.to_meta()) == scaled and "scale" not in one.to_meta()
    # in a synchronizer the left hand keeps its scale and the right hand plays as it is
    sync, norm = PO.init_synchronizer(jax.random.PRNGKey(3), left, right, DUET)
    params = {"policy": sync, "obs_norm": norm, "frozen": {"left": left, "right": right}}
    duet = jax.random.normal(jax.random.PRNGKey(4), (3, 902))
    plain, _ = PO.distribution(SPEC, params, duet)
    shrunk, _ = PO.distribution(PO.PolicySpec("synchronizer", "duet", 54, DUET, 9, 0.01), params, duet)
    np.testing.assert_allclose(shrunk[:, :27], 0.01 * plain[:, :27], rtol=1e-5, atol=1e-9)
    np.testing.assert_array_equal(shrunk[:, 27:], plain[:, 27:])
    # a run starts from a policy only at the same scale
    PO.export(tmp_path / "scaled", left, lmeta | scaled.to_meta())
    assert check_init(tmp_path / "scaled", "left", 9, 0.01)["scale"] == 0.01
    with pytest.raises(UserError, match="scaled by 0.01.*action_scale is 1.0"):
        check_init(tmp_path / "scaled", "left", 9)


def test_a_cpu_plays_the_duet_a_few_songs_at_a_time(tmp_path, monkeypatch):
    """Five or six songs in one duet program stalled XLA's CPU run on a 2-core machine, so a CPU plays the duet
    `CPU_DUET_SONGS` songs at a time. Here one at a time, with the shipped general pair: two songs take the
    one-song program, the first scores exactly as it does alone, and two songs of one title keep apart by their
    place. Songs not planned yet are planned together, in one pool of planner processes, before the first plays."""
    from dexguitar.cli import POLICIES
    from dexguitar.planner import plans as FF
    from dexguitar.music import load_song
    from dexguitar.perform import evaluate as EV
    from dexguitar.perform.play import pair as general_pair
    params, spec = general_pair(POLICIES / "left_general", POLICIES / "right_mixed")
    (tmp_path / "tiny.txt").write_text(TINY_SONG)
    (tmp_path / "other.txt").write_text(TINY_SONG.replace("B|----1", "B|----3"))      # the same title
    song, other = load_song(tmp_path / "tiny.txt"), load_song(tmp_path / "other.txt")
    monkeypatch.setattr(EV, "CPU_DUET_SONGS", 1)
    monkeypatch.setattr(EV, "_CACHE", {})
    one = EV.evaluate(params, spec, [song])
    assert one[song.title]["summary"]["both"]["notes"] == 3                  # two notes and a chord, all judged
    monkeypatch.setenv("DEXGUITAR_PLANS", str(tmp_path / "plans"))
    pools = []
    plan_all = FF.plan_all
    monkeypatch.setattr(FF, "plan_all", lambda jobs, *a, **k: pools.append(len(jobs)) or plan_all(jobs, *a, **k))
    two = EV.evaluate(params, spec, [song, other])
    assert pools == [2] and len(EV._CACHE) == 1                 # one pool; a single program, of one song's shape
    assert list(two) == [song.title, f"{song.title} (1)"]
    assert two[song.title] == one[song.title] and two[f"{song.title} (1)"] != one[song.title]


def test_pair_is_checked(pair):
    (left, lmeta), (right, rmeta) = pair
    with pytest.raises(UserError, match="RIGHT: a policy for the left hand"):
        PO.check_pair(lmeta, lmeta, DUET)
    with pytest.raises(UserError, match="action size 54"):
        PO.check_pair(dict(lmeta, action_size=54), rmeta, DUET)
    PO.check_pair(lmeta, rmeta, DUET)


@pytest.fixture(scope="module")
def sync_trainer(pair, tmp_path_factory):
    from dexguitar.learn.trainer import TrainConfig
    from dexguitar.motion import load_motion
    from dexguitar.motion.kinematics import reference_frames
    from dexguitar.music import load_song
    from dexguitar.music import timeline as TL
    base = tmp_path_factory.mktemp("sync")
    path = base / "tiny.txt"
    path.write_text(TINY_SONG)
    for (params, meta), name in zip(pair, ("left", "right")):
        PO.export(base / name, params, meta)
    cfg = TrainConfig(hand="duet", num_envs=4, horizon=4, minibatch=8, epochs=2, disc_steps=2, disc_buffer=64,
                      disc_batch=16, iterations_per_call=1)
    return SY.SyncTrainer(cfg, [TL.from_song(load_song(path))], reference_frames(load_motion("left")),
                          *PO.load_pair(base / "left", base / "right"))


def test_sync_iteration_trains_only_the_synchronizer_and_resumes_exactly(sync_trainer, tmp_path, compiled_chunk):
    t = sync_trainer
    assert t.columns == tuple(f"string{i}" for i in range(1, 7)) + ("pick", "disc_wrist", "disc_fingers")
    np.testing.assert_allclose(t.weights, [0.15] * 6 + [1.0, 0.05, 0.05])
    assert abs(float(jnp.sum(t.weights)) - 2.0) < 1e-6                  # reference §5.3: they sum to 2
    chunk, start, data, put = compiled_chunk(t, t.init())
    p0 = jax.device_get(start.params)
    first, metrics = chunk(start, data)
    assert all(np.isfinite(float(v)) for k, v in metrics.items() if not k.startswith("f1/"))
    # the duet env's 4 states after the iteration's steps: both hands' observations, 7 reward columns
    env = first.env
    chex.assert_shape(env.obs, (4, 2 * 2 * 16 * 13 + 2 * 35))
    chex.assert_shape(env.reward, (4, 7))
    chex.assert_shape(env.privileged, (4, 6))
    chex.assert_tree_all_finite((env.obs, env.reward))
    assert t.env.layout.obs_size == 902 and t.env.layout.hands == 2 and t.env.layout.frame == 16 * 13
    # a strum asks for contiguous strings: each note's target strings are one run
    for row in np.asarray(env.cursor.window.pick).reshape(-1, 6):
        on = np.flatnonzero(row)
        assert len(on) == 0 or on[-1] - on[0] + 1 == len(on), row
    p1 = jax.device_get(first.params)
    diff = jax.tree.map(lambda a, b: float(np.abs(np.asarray(a) - b).max()), p1, p0)
    assert max(jax.tree.leaves(diff["policy"]["params"]["dz"])) > 0           # the synchronizer learns
    assert max(jax.tree.leaves(diff["critic"])) > 0
    assert max(jax.tree.leaves(diff["frozen"])) == 0.0                         # both policies stay as they were
    assert p1["critic"]["params"]["value"]["kernel"].shape[-1] == 9
    C.save(tmp_path / "ckpt", int(first.iteration), first)
    template = jax.tree.map(jnp.zeros_like, first)          # a fresh process's structure, without building it
    uninterrupted, _ = chunk(first, data)
    resumed, _ = chunk(put(C.restore(tmp_path / "ckpt", template)[0]), data)
    same = jax.tree.map(lambda a, b: np.array_equal(np.asarray(a), np.asarray(b)), resumed, uninterrupted)
    assert all(jax.tree.leaves(same))


def test_export_plays_before_and_after(sync_trainer, tmp_path):
    from dexguitar.learn.run import export
    state = sync_trainer.init()
    export(sync_trainer, state, tmp_path / "policy")
    meta = json.loads((tmp_path / "policy" / "policy.json").read_text())
    assert meta["kind"] == "synchronizer" and meta["action_size"] == 54
    assert meta["sources"]["left"]["path"].endswith("left")           # the export names the policies it shifts
    params, meta = PO.load(tmp_path / "policy")
    before = PO.make_act(PO.unsynchronized(params), meta)
    after = PO.make_act(params, meta)
    obs = jax.random.normal(jax.random.PRNGKey(0), (3, 2 * 416 + 70))
    np.testing.assert_allclose(before(obs), after(obs), atol=1e-6)             # untrained: the same actions
    actor = sync_trainer.actor_params(state.params, state.obs_norm)
    mu, _ = PO.distribution(sync_trainer.spec, actor, obs)
    # the export stores the synchronizer's weights as float16 (the frozen policies load from their own exports)
    np.testing.assert_allclose(after(obs), mu, atol=2e-3)


def test_sync_command_end_to_end(tmp_path, capsys, monkeypatch, export_compiles):
    """Also: the second host call of a sync run compiles nothing."""
    from dexguitar.cli import main
    dirs = []
    calm = random_policy(jax.random.PRNGKey(1), "left", 0.0), random_policy(jax.random.PRNGKey(2), "right", 0.0)
    for (params, meta), name in zip(calm, ("left", "right")):
        PO.export(tmp_path / name, params, meta)
        dirs.append(str(tmp_path / name))
    song = tmp_path / "tiny.txt"
    song.write_text(TINY_SONG)
    out = tmp_path / "run"
    args = ["sync", "--song", str(song), "--left", dirs[0], "--right", dirs[1], "--config",
            "cpu_smoke", "--out", str(out), "--seed", "3"]
    assert main(args + ["--iterations", "2", "--no-eval"]) == 0        # two host calls (`iterations_per_call` 1)
    assert len(export_compiles) == 2 and export_compiles[1] == export_compiles[0]      # the second compiled nothing
    capsys.readouterr()
    assert main(args + ["--iterations", "2", "--no-eval"]) == 2
    assert "--resume" in capsys.readouterr().err
    # resume with the policies recorded in the run (nothing left to train); the before/after evaluation that `sync`
    # ends with runs in tests/test_notebooks.py (synchronize.ipynb) and test_export_plays_before_and_after
    assert main(["sync", "--song", str(song), "--config", "cpu_smoke", "--out", str(out),
                 "--seed", "3", "--resume", "--iterations", "2", "--no-eval"]) == 0
    assert [json.loads(x)["iteration"] for x in (out / "metrics.jsonl").read_text().splitlines()] == [1, 2]
    capsys.readouterr()
    # a seed other than the run's refuses, naming it; with nothing but --out, the run goes on as config.json has it
    # (songs, config, seed and policies), from any working directory
    assert main(["sync", "--out", str(out), "--resume", "--seed", "4", "--no-eval"]) == 2
    assert "train.seed: 3 -> 4" in capsys.readouterr().err
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    assert main(["sync", "--out", str(out), "--resume", "--iterations", "3", "--no-eval"]) == 0
    assert [json.loads(x)["iteration"] for x in (out / "metrics.jsonl").read_text().splitlines()] == [1, 2, 3]
    meta = json.loads((out / "policy" / "policy.json").read_text())
    assert meta["kind"] == "synchronizer" and meta["sources"]["right"]["path"] == "../../right"


def test_shipped_general_left_hand_is_the_planner_with_noise_it_survives():
    """A synchronizer trains on actions sampled from the frozen hands' Gaussians. The shipped zero residual's mean is
    the planner (0); its std must stay where the planner keeps its F1 (docs/results.md: 0.002 costs 0.02 of
    window F1, 0.02 costs 0.36), not the log-std head's zero bias (std 1) nor the residual recipe's 0.02."""
    from dexguitar.cli import POLICIES
    params, meta = PO.load(POLICIES / "left_general")
    spec = PO.PolicySpec.from_meta(meta)
    obs = jax.random.normal(jax.random.PRNGKey(3), (5, meta["obs_size"]))
    mu, log_std = PO.distribution(spec, params, obs)
    assert float(jnp.max(jnp.abs(mu))) == 0.0
    np.testing.assert_allclose(np.exp(np.asarray(log_std)), np.exp(-6.2), rtol=1e-2)     # 0.00203


@pytest.mark.parametrize("song", ["flight_of_the_bumblebee1", "snow"])
def test_shipped_gsync_synchronizer_loads_the_shipped_general_pair(song):
    """models/policies/gsync_<stem> names its frozen hands relative to itself, so a clone plays it as shipped, with
    the planner version it was trained on."""
    from dexguitar.cli import POLICIES, gsync_for
    path = gsync_for(f"../shared/data/official/notes/{song}.json")
    assert path == POLICIES / f"gsync_{song}"
    params, meta = PO.load(path)
    assert meta["kind"] == "synchronizer" and meta["feedforward"] == 21
    assert {side: meta["sources"][side]["path"] for side in ("left", "right")} == {
        "left": "../left_general", "right": "../right_mixed"}
    general = {side: PO.load(POLICIES / name)[0] for side, name in (("left", "left_general"), ("right", "right_mixed"))}
    for side in ("left", "right"):
        for a, b in zip(jax.tree.leaves(params["frozen"][side]), jax.tree.leaves(general[side])):
            np.testing.assert_array_equal(a, b)
