"""The `dexguitar` command on songs: info, convert, clear errors."""
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
