"""`dexguitar songs` (perform/pipeline.py): which policy each stage starts from, the minutes a resumed stage has left,
that finished stages are skipped, and how the judge keeps the best export. Training and playing are replaced by
recorders, so nothing compiles here."""
import json

import pytest

from dexguitar.perform import pipeline as P


class Recorder:
    """Stands in for `run.train`: records its arguments and writes the files a real run leaves behind."""

    def __init__(self):
        self.calls = []

    def __call__(self, trainer, run_dir, iterations, resume, meta, max_minutes, init_from, on_call, log):
        self.calls.append({"stage": run_dir.name, "resume": resume, "minutes": max_minutes, "init_from": init_from})
        run_dir.mkdir(parents=True, exist_ok=True)
        (run_dir / "config.json").write_text("{}")
        # one host call of 30 s after a compilation of 30 s: one minute spent
        (run_dir / "metrics.jsonl").write_text(json.dumps({"seconds": 30.0, "compile_s": 30.0}) + "\n")
        return {"samples": 1}


@pytest.fixture
def recorder(monkeypatch):
    rec = Recorder()
    monkeypatch.setattr(P, "train", rec)
    monkeypatch.setattr(P, "Trainer", lambda *a, **k: None)
    monkeypatch.setattr(P, "SyncTrainer", lambda *a, **k: None)
    monkeypatch.setattr(P.PO, "load_pair", lambda *a: (None, None))
    return rec


def test_the_left_and_right_stages_start_from_the_recipes_policies(recorder, tmp_path):
    recipe = P.Recipe(left_init="L0", right_init="R0", left_minutes=3.0, right_minutes=2.0, sync_minutes=5.0)
    book = P.Songbook(tmp_path, "g", ["ode_to_joy"], recipe, log=lambda m: None)
    for stage in P.STAGES:
        book.run(stage)
    assert [(c["stage"], c["init_from"], c["minutes"]) for c in recorder.calls] == [
        ("left", "L0", 3.0), ("right", "R0", 2.0), ("sync", None, 5.0)]
    # each stage recorded the minute it spent (30 s of training + 30 s of compilation)
    done = json.loads((tmp_path / "g" / "stages.json").read_text())["done"]
    assert {s: round(d["minutes"], 6) for s, d in done.items()} == {"left": 1.0, "right": 1.0, "sync": 1.0}


def test_a_hand_stage_of_zero_minutes_hands_its_starting_policy_on_untrained(recorder, tmp_path):
    start = tmp_path / "R0"
    start.mkdir()
    (start / "policy.json").write_text('{"hand": "right"}')
    (start / "params.bin").write_bytes(b"\x01\x02")
    recipe = P.Recipe(left_init="L0", right_init=str(start), right_minutes=0.0)
    book = P.Songbook(tmp_path / "out", "g", ["ode_to_joy"], recipe, log=lambda m: None)
    book.run("right")
    assert recorder.calls == []                                   # nothing trained
    best = P.best_export(tmp_path / "out" / "g" / "right")
    assert best == tmp_path / "out" / "g" / "right" / "best"
    assert (best / "params.bin").read_bytes() == b"\x01\x02"
    assert json.loads((tmp_path / "out" / "g" / "stages.json").read_text())["done"]["right"] == {"minutes": 0.0}
    with pytest.raises(P.UserError, match="no policy to start from"):
        P.Songbook(tmp_path / "out", "h", ["ode_to_joy"], P.Recipe(left_init=None, left_minutes=0.0),
                   log=lambda m: None).run("left")


def test_a_left_hand_from_scratch_and_the_default_warm_start(recorder, tmp_path):
    P.Songbook(tmp_path, "a", ["ode_to_joy"], P.Recipe(left_init=None), log=lambda m: None).run("left")
    assert recorder.calls[-1]["init_from"] is None
    default = P.Recipe()
    assert default.left_init.endswith("models/policies/left_official15")
    assert default.left_config == "left_finetune"                       # dexguitar/configs/left_finetune.py
    P.Songbook(tmp_path, "b", ["ode_to_joy"], default, log=lambda m: None).run("left")
    assert recorder.calls[-1]["init_from"] == default.left_init


def test_an_interrupted_stage_resumes_with_the_minutes_it_has_left_and_a_done_one_is_skipped(recorder, tmp_path):
    recipe = P.Recipe(left_init="L0", left_minutes=3.0)
    run_dir = tmp_path / "g" / "left"
    run_dir.mkdir(parents=True)
    (run_dir / "config.json").write_text("{}")
    # two host calls of 20 s in a process that compiled for 20 s: 1 minute spent, 2 left
    (run_dir / "metrics.jsonl").write_text("".join(json.dumps({"seconds": 20.0, "compile_s": 20.0}) + "\n"
                                                   for _ in range(2)))
    book = P.Songbook(tmp_path, "g", ["ode_to_joy"], recipe, log=lambda m: None)
    book.run("left")
    assert recorder.calls == [{"stage": "left", "resume": True, "minutes": pytest.approx(2.0), "init_from": None}]
    book.run("left")
    assert len(recorder.calls) == 1


def songs_recipe(args, monkeypatch, tmp_path):
    """The `Recipe` that `dexguitar songs ARGS` hands to the pipeline (which is not run)."""
    from dexguitar import cli
    seen = {}

    def fake_run_songs(tabs, out, recipe, per_song):
        seen["recipe"] = recipe
        (tmp_path / "songs.md").write_text("")
        return [{}]
    monkeypatch.setattr(cli.pipeline, "run_songs", fake_run_songs)
    assert cli.main(["songs"] + args + ["--out", str(tmp_path)]) == 0
    return seen["recipe"]


@pytest.mark.parametrize("flag, expected", [([], P.Recipe().left_init), (["--left-init", "none"], None),
                                            (["--left-init", "my/left"], "my/left")])
def test_the_songs_command_passes_the_left_start_on(flag, expected, monkeypatch, tmp_path):
    assert songs_recipe(["ode_to_joy"] + flag, monkeypatch, tmp_path).left_init == expected


class Exports:
    """Stands in for loading and writing exports: an export is its policy.json; the parameters are its meta."""

    def __init__(self, monkeypatch):
        monkeypatch.setattr(P.PO, "load", lambda d: (json.loads((d / "policy.json").read_text()),) * 2)
        monkeypatch.setattr(P.PO, "export", self.export)
        monkeypatch.setattr(P.PO, "unsynchronized", lambda params: dict(params, dz="zero"))

    @staticmethod
    def export(directory, params, meta):
        directory.mkdir(parents=True)
        (directory / "policy.json").write_text(json.dumps(dict(meta, dz=params.get("dz"))))


def judge_with(monkeypatch, run, scores: dict, kind="policy", target=0.95, every_s=0.0):
    """A judge whose F1 of an export is scores[(iteration, dz)]."""
    Exports(monkeypatch)
    monkeypatch.setattr(P.Judge, "score", lambda self, params, meta: scores[(params["iteration"], params.get("dz"))])
    run.mkdir(parents=True, exist_ok=True)
    return P.Judge(run, songs=[], target=target, every_s=every_s, log=lambda m: None), kind


def write_export(run, iteration, kind):
    (run / "policy").mkdir(parents=True, exist_ok=True)
    (run / "policy" / "policy.json").write_text(json.dumps({"iteration": iteration, "kind": kind}))


def test_the_judge_keeps_the_best_export_and_stops_at_the_target(monkeypatch, tmp_path):
    run = tmp_path / "left"
    judge, kind = judge_with(monkeypatch, run, {(25, None): 0.5, (50, None): 0.9, (75, None): 0.7,
                                                (100, None): 0.96})
    write_export(run, 25, kind)
    assert P.best_export(run) == run / "policy"            # nothing judged yet: the last export
    stops = []
    for it in (25, 50, 75):
        write_export(run, it, kind)
        stops.append(judge(it))
    assert stops == [False, False, False]
    assert json.loads((run / "best" / "policy.json").read_text())["iteration"] == 50
    assert P.best_export(run) == run / "best"
    write_export(run, 100, kind)
    assert judge(100) is True                              # 0.96 >= 0.95
    state = json.loads((run / "judge.json").read_text())
    assert [h["iteration"] for h in state["history"]] == [25, 50, 75, 100]
    assert state["best"] == {"iteration": 100, "f1": 0.96}
    # a resumed stage knows its best, and an iteration already judged is not played again
    again = P.Judge(run, songs=[], target=0.95, every_s=0.0, log=lambda m: None)
    assert again.reached() and again(100) and len(again.state["history"]) == 4


def test_the_judge_waits_between_judgements_unless_forced(monkeypatch, tmp_path):
    run = tmp_path / "left"
    judge, kind = judge_with(monkeypatch, run, {(25, None): 0.5, (50, None): 0.6}, every_s=3600.0)
    write_export(run, 25, kind)
    assert judge(25) is False and not (run / "judge.json").exists()   # not yet an hour
    assert judge(25, force=True) is False
    assert json.loads((run / "judge.json").read_text())["best"]["iteration"] == 25


def test_a_synchronizer_that_plays_worse_than_the_pair_alone_is_not_kept(monkeypatch, tmp_path):
    run = tmp_path / "sync"
    judge, kind = judge_with(monkeypatch, run, {(25, "zero"): 0.94, (25, None): 0.90, (50, None): 0.92},
                             kind="synchronizer")
    for it in (25, 50):
        write_export(run, it, kind)
        judge(it)
    best = json.loads((run / "best" / "policy.json").read_text())
    assert best["unsynchronized"] is True and best["dz"] == "zero"
    assert [(h["iteration"], h["f1"]) for h in judge.state["history"]] == [
        ("unsynchronized", 0.94), (25, 0.90), (50, 0.92)]


def test_a_synchronizer_still_in_its_warm_up_is_judged_once_as_the_pair_alone(monkeypatch, tmp_path):
    run = tmp_path / "sync"
    judge, kind = judge_with(monkeypatch, run, {(25, "zero"): 0.80, (75, None): 0.85}, kind="synchronizer")
    judge.frozen_until = 50
    for it in (25, 50, 75):
        write_export(run, it, kind)
        judge(it)
    assert [(h["iteration"], h["f1"]) for h in judge.state["history"]] == [("unsynchronized", 0.80), (75, 0.85)]


def test_the_minutes_of_a_stage_count_its_judgements(tmp_path):
    run = tmp_path / "left"
    run.mkdir()
    (run / "metrics.jsonl").write_text(json.dumps({"seconds": 30.0, "compile_s": 15.0}) + "\n")
    (run / "judge.json").write_text(json.dumps({"best": None, "history": [], "seconds": 15.0}))
    assert P._spent(run) == pytest.approx(1.0)


def test_each_stage_trains_with_its_config_and_overrides(recorder, monkeypatch, tmp_path):
    """`songs --set` reaches every stage, `--set-<stage>` its own; a stage's config is a name in dexguitar/configs/."""
    recipe = songs_recipe(["ode_to_joy", "--set", "seed=3", "--set-sync", "env.hold_reward=0.5", "--set-sync",
                           "actor_warmup=7"], monkeypatch, tmp_path)
    assert recipe.left_set == recipe.right_set == ("seed=3",)
    assert recipe.sync_set == ("seed=3", "env.hold_reward=0.5", "actor_warmup=7")
    built = {}
    monkeypatch.setattr(P, "Trainer", lambda cfg, songs, ref, env: built.update(left=(cfg, env)))
    monkeypatch.setattr(P, "SyncTrainer", lambda cfg, songs, ref, left, right, env: built.update(sync=(cfg, env)))
    book = P.Songbook(tmp_path / "out", "g", ["ode_to_joy"], recipe, log=lambda m: None)
    book.run("left")
    book.run("sync")
    cfg, env = built["left"]
    assert (cfg.hand, cfg.seed, cfg.actor_warmup, cfg.clip, env.shift_prob) == ("left", 3, 25, 0.3, 0.0)   # finetune
    cfg, env = built["sync"]
    assert (cfg.hand, cfg.seed, cfg.actor_warmup, env.hold_reward) == ("duet", 3, 7, 0.5)
    with pytest.raises(P.UserError, match="--set clip=high: config left_finetune: TrainConfig.clip is a number"):
        P.Songbook(tmp_path / "out2", "g", ["ode_to_joy"], P.Recipe(left_set=("clip=high",)),
                   log=lambda m: None).run("left")
