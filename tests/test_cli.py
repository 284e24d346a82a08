"""The `dexguitar` command: songs (info, convert), clear errors, configs by name with `--set` overrides."""
import dataclasses
import json
import os
import sys

import pytest

from dexguitar.cli import main


def test_song_info_json_on_an_embedded_song(capsys):
    assert main(["song", "info", "ode_to_joy", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    # 16 bars of 4/4 at 120 BPM = 64 beats = 32 s = 1920 frames at 60 Hz; quarter notes = 30 frames each
    assert info["tempo"] == 120 and info["seconds"] == pytest.approx(32.0) and info["frames"] == 1920
    assert {"tempo", "notes", "chords", "seconds", "frames", "frets"} <= set(info)
    assert info["chords"] == 0 and info["frets"][0] >= 1


def test_song_convert_round_trip(tmp_path, capsys):
    out = tmp_path / "barre.json"
    assert main(["song", "convert", "barre_f_bm", str(out)]) == 0
    capsys.readouterr()
    assert main(["song", "info", str(out), "--json"]) == 0
    converted = json.loads(capsys.readouterr().out)
    assert main(["song", "info", "barre_f_bm", "--json"]) == 0
    original = json.loads(capsys.readouterr().out)
    for key in ("tempo", "notes", "chords", "seconds", "frames", "frets"):
        assert converted[key] == original[key]


def test_bad_input_is_one_clear_line(tmp_path, capsys):
    bad = tmp_path / "bad.txt"
    bad.write_text("tempo: 100\ne|--0--|\nB|--1--|\nG|--0--|\n")     # a system of 3 lines
    assert main(["song", "info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "bad.txt" in err and "line 2" in err
    assert main(["song", "info", str(tmp_path / "missing.gp5")]) == 2
    assert "missing.gp5" in capsys.readouterr().err


def test_procedural_material_by_style():
    from dexguitar.errors import UserError
    from dexguitar.music.procedural import material
    mixed = material("right", "mixed", 0, 5)
    assert [s.title.split("-")[0] for s in mixed] == ["right", "right", "right", "paper", "paper"]
    assert all(s.tempo == 225 for s in material("right", "paper", 0, 3))
    assert len(material("left", "exercises", 0, 2)) == 2
    assert len(material("left", None, 0, 3)) == 3                         # the left hand's default: general
    with pytest.raises(UserError, match="not a left-hand style"):
        material("left", "paper", 0, 2)


# A command that fails while a chunk is still compiling in its thread (a sleep of a minute stands for the compile).
STILL_COMPILING = """
import concurrent.futures, sys, time
from dexguitar import cli
from dexguitar.errors import UserError
from dexguitar.learn import executable
executable._submit(concurrent.futures.ThreadPoolExecutor(1), time.sleep, 60)
def fail(args):
    raise UserError("a bad song, found after the chunk's compile started")
cli._check = fail
sys.argv = ["dexguitar", "check"]
sys.exit(cli.main())
"""


def test_a_command_that_fails_while_its_chunk_compiles_exits_at_once():
    """A failure or Ctrl-C after the training chunk's compile started used to wait for that compile at exit (a minute
    on a fresh GPU); now the process ends at once, with the command's exit code and its error printed."""
    import subprocess
    import time
    t = time.monotonic()
    done = subprocess.run([sys.executable, "-c", STILL_COMPILING], capture_output=True, text=True, timeout=120,
                          env={**os.environ, "JAX_PLATFORMS": "cpu"})
    assert done.returncode == 2, done.stderr
    assert "error: a bad song" in done.stderr
    assert time.monotonic() - t < 40          # not the 60 s of the "compile"


# ------------------------------------------------------------------------------------- configs: --config and --set

def test_every_shipped_config_loads_by_name_and_by_path():
    """Each module of dexguitar/configs/ says what it is for and defines CONFIG (and optionally ENV); a name and the
    module's path give the same config."""
    from pathlib import Path
    from dexguitar import configs
    from dexguitar.envs import EnvConfig
    from dexguitar.configs import load_config
    from dexguitar.learn.trainer import TrainConfig
    names = configs.names()
    assert {"cpu_smoke", "left_gpu", "right_gpu", "sync_gpu", "sync_hold", "left_finetune", "left_songs",
            "right_songs", "left_general_anchored"} <= set(names)
    for name in names:
        module = configs.load(name)
        assert module.__doc__ and len(module.__doc__) > 40, name
        assert isinstance(module.CONFIG, TrainConfig) and isinstance(getattr(module, "ENV", None),
                                                                     (EnvConfig, type(None))), name
        path = str(Path(configs.__file__).parent / f"{name}.py")
        assert load_config(name) == load_config(path), name
    assert load_config("sync_hold")[1].hold_reward == 1.0


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    return err[0]


def test_an_unknown_config_or_field_is_one_line_naming_it(tmp_path, capsys):
    run = ["train", "--song", "ode_to_joy", "--out", str(tmp_path / "run")]
    assert main(run + ["--config", "left_gpuu"]) == 2
    err = one_error_line(capsys)
    assert "--config left_gpuu: no such config" in err and "cpu_smoke, " in err and "sync_hold" in err
    assert main(run + ["--config", "experiments/left_gpu.py"]) == 2          # where the configs were
    assert "--config left_gpu" in one_error_line(capsys)
    assert main(run + ["--config", "cpu_smoke", "--set", "num_envz=8"]) == 2
    err = one_error_line(capsys)
    assert "--set num_envz: config cpu_smoke has no such field" in err and "num_envs" in err
    assert main(run + ["--config", "left_songs", "--set", "env.shift=0"]) == 2
    assert "--set env.shift: config left_songs has no such field" in one_error_line(capsys)
    for bad, why in (("num_envs=many", "TrainConfig.num_envs is an integer, not 'many'"),
                     ("clip=inf", "TrainConfig.clip is a finite number, not 'inf'"),
                     ("env.fill_strum_gaps=perhaps", "EnvConfig.fill_strum_gaps is true or false, not 'perhaps'"),
                     ("env.window_notes=10", "EnvConfig.window_notes is 2 values separated by commas, not '10'"),
                     ("num_envs", "expected KEY=VALUE"),
                     ("num_envs=0", "TrainConfig.num_envs must be at least 1, got 0")):
        assert main(run + ["--config", "cpu_smoke", "--set", bad]) == 2
        err = one_error_line(capsys)
        assert f"--set {bad}" in err and "cpu_smoke" in err and why in err, err
    assert main(run + ["--config", "cpu_smoke", "--set", "num_envs=8", "--envs", "4"]) == 2
    assert "--set num_envs=8 disagrees with the command's own num_envs 4" in one_error_line(capsys)


def test_set_reaches_the_trainer(tmp_path, monkeypatch):
    """`--set` overrides CONFIG's fields and ENV's as env.KEY, parsed to each field's type; an env field of a config
    without ENV starts from the env's defaults (the synchronizer's for `sync`)."""
    from dexguitar import cli
    built = {}

    class Built(Exception):
        pass

    def trainer(cfg, songs, reference, *rest):          # rest: (frozen pair,) env config, devices
        from dexguitar.envs import EnvConfig
        (env,) = [r for r in rest if isinstance(r, EnvConfig)]
        built.update(cfg=cfg, env=env)
        raise Built
    monkeypatch.setattr(cli, "Trainer", trainer)
    monkeypatch.setattr(cli, "SyncTrainer", trainer)
    monkeypatch.setattr(cli.PO, "load_pair", lambda left, right: (None, None))
    with pytest.raises(Built):
        main(["train", "--song", "ode_to_joy", "--out", str(tmp_path / "a"), "--config", "left_songs", "--set",
              "clip=0.25", "--set", "iterations_per_call=3", "--set", "env.window_notes=4,8", "--set",
              "env.fill_strum_gaps=false"])
    cfg, env = built["cfg"], built["env"]
    assert (cfg.clip, cfg.iterations_per_call, cfg.num_envs) == (0.25, 3, 4096)
    assert (env.window_notes, env.fill_strum_gaps, env.shift_prob) == ((4, 8), False, 0.0)    # the rest: left_songs
    with pytest.raises(Built):
        main(["sync", "--song", "ode_to_joy", "--left", "L", "--right", "R", "--out", str(tmp_path / "b"),
              "--config", "cpu_smoke", "--set", "env.hold_reward=0.5", "--set", "seed=7"])
    from dexguitar.learn.sync import SYNC_ENV
    assert built["cfg"].seed == 7 and built["cfg"].hand == "duet"
    assert built["env"] == dataclasses.replace(SYNC_ENV, hold_reward=0.5)


def test_the_overrides_are_recorded_and_checked_on_resume(tmp_path):
    """A run records its config with the overrides applied (config.json's "train" and "env"), so --resume with
    other overrides is refused naming the field, and `sync --resume` without --config takes them from there."""
    from dexguitar.errors import RunError
    from dexguitar.configs import load_config, recorded_config
    from dexguitar.learn.run import RunDir
    record = lambda cfg, env: json.loads(json.dumps({"train": dataclasses.asdict(cfg),       # noqa: E731
                                                     "env": dataclasses.asdict(env)}))
    made = record(*load_config("left_songs", ["clip=0.25", "env.tempo_delta=10"]))
    (tmp_path / "config.json").write_text(json.dumps(made))
    run = RunDir(tmp_path)
    try:
        run.check_resume(record(*load_config("left_songs", ["clip=0.25", "env.tempo_delta=10"])))
        with pytest.raises(RunError, match=r"env\.tempo_delta: 10 -> 20; train\.clip: 0\.25 -> 0\.3"):
            run.check_resume(record(*load_config("left_songs")))
        cfg, env = recorded_config(made, ["seed=5"])
        assert (cfg.clip, cfg.seed, env.tempo_delta) == (0.25, 5, 10)
    finally:
        run.close()


def test_the_shipped_policies_are_found_in_one_place(tmp_path, monkeypatch):
    from dexguitar import shipped
    monkeypatch.delenv(shipped.POLICIES_ENV, raising=False)
    assert (shipped.policies_dir() / "left_general" / "policy.json").exists()
    monkeypatch.setenv(shipped.POLICIES_ENV, str(tmp_path))
    assert shipped.policies_dir() == tmp_path


@pytest.mark.parametrize("argv, every", [([], 60.0), (["--save-every", "0"], 0.0), (["--save-every", "300"], 300.0)])
def test_save_every_reaches_the_training_loop(argv, every, tmp_path, monkeypatch):
    from dexguitar import cli
    seen = {}
    monkeypatch.setattr(cli, "train", lambda trainer, out, **kw: seen.update(kw) or {"iteration": 0})
    assert main(["train", "--song", "ode_to_joy", "--config", "cpu_smoke", "--out", str(tmp_path / "r")] + argv) == 0
    assert seen["save_every"] == every
