"""The `dexguitar` command on songs: info, convert, clear errors."""
import json

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
