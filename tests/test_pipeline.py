"""`dexguitar songs` (perform/pipeline.py): which policy each stage starts from, the minutes a resumed stage has left,
and that finished stages are skipped. Training itself is replaced by a recorder, so nothing compiles here."""
import json

import pytest

from dexguitar.perform import pipeline as P


class Recorder:
    """Stands in for `run.train`: records its arguments and writes the files a real run leaves behind."""

    def __init__(self):
        self.calls = []

    def __call__(self, trainer, run_dir, iterations, resume, meta, max_minutes, init_from, stop_f1, log):
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


def test_a_left_hand_from_scratch_and_the_default_warm_start(recorder, tmp_path):
    P.Songbook(tmp_path, "a", ["ode_to_joy"], P.Recipe(left_init=None), log=lambda m: None).run("left")
    assert recorder.calls[-1]["init_from"] is None
    default = P.Recipe()
    assert default.left_init.endswith("models/policies/left_official15")
    assert default.left_config.endswith("experiments/left_finetune.py")
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


@pytest.mark.parametrize("flag, expected", [([], P.Recipe().left_init), (["--left-init", "none"], None),
                                            (["--left-init", "my/left"], "my/left")])
def test_the_songs_command_passes_the_left_start_on(flag, expected, monkeypatch, tmp_path):
    from dexguitar import cli
    seen = {}

    def fake_run_songs(tabs, out, recipe, per_song):
        seen["recipe"] = recipe
        (tmp_path / "songs.md").write_text("")
        return [{}]
    monkeypatch.setattr(cli.pipeline, "run_songs", fake_run_songs)
    assert cli.main(["songs", "ode_to_joy", "--out", str(tmp_path)] + flag) == 0
    assert seen["recipe"].left_init == expected
