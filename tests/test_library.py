"""Embedded songs: they load, are playable, and together cover the techniques the experiments need; `load_songs`."""
import json
from fractions import Fraction as F

import pytest

from dexguitar.music import library, load_song
from dexguitar.music.library import load_songs
from dexguitar.music.song import MUTE, Effect, SongError

EXPECTED = {"ode_to_joy", "twinkle", "greensleeves", "minuet_in_g", "spanish_romance", "rising_sun",
            "amazing_grace", "chromatic_1234", "c_major_scale", "open_strings", "strum_g_c_d", "barre_f_bm",
            "high_frets"}


@pytest.fixture(scope="module")
def songs():
    return {name: library.load(name) for name in library.names()}


def test_names_and_paths():
    names = library.names()
    assert names == sorted(names) and len(names) >= 12
    assert EXPECTED <= set(names)
    for name in names:
        assert library.path(name).is_file() and library.path(name).stem == name
    with pytest.raises(SongError, match="no embedded song named 'nope'"):
        library.path("nope")
    with pytest.raises(SongError):
        library.load("../library")


def test_headers(songs):
    for name in library.names():
        text = library.path(name).read_text()
        for key in ("title:", "tempo:", "grid:", "\n# "):
            assert key in text, (name, key)
        assert songs[name].title and songs[name].title != name


def pressed_span(frets):
    pressed = [f for f in frets if f > 0]
    return max(pressed) - min(pressed) if pressed else 0


def test_every_song_is_playable(songs):
    for name, song in songs.items():
        assert 8 <= song.seconds <= 40, (name, song.seconds)
        assert song.n_notes >= 10, name
        for note in song.notes:
            assert F(1, 16) <= note.duration <= F(2), (name, note)
            assert all(f <= 22 for f in note.frets)
            assert pressed_span(note.frets) <= 3, (name, note.frets)      # within a 4-fret span
            if note.chord is not None:
                assert pressed_span(note.chord) <= 3, (name, note.chord)
                # the picked strings agree with the held shape
                assert all(c == f for f, c in zip(note.frets, note.chord) if f != MUTE), (name, note)


def test_coverage(songs):
    notes = [(name, n) for name, s in songs.items() for n in s.notes]

    def barre(n):
        return any(n.frets[0] == n.frets[5] == f and n.frets.count(f) >= 3 for f in set(n.frets) if f > 0)

    assert any(barre(n) for _, n in notes)                                        # barre chord
    assert any(s.tempo >= 150 for s in songs.values())                            # fast passage
    assert any(f >= 12 for _, n in notes for f in n.frets)                        # high frets
    assert any(n.chord is not None and len(n.played) == 1 for _, n in notes)     # arpeggio with chord hints
    assert any(n.is_chord and n.frets == m.frets for s in songs.values()
               for n, m in zip(s.notes, s.notes[1:]))                             # strumming
    assert any(0 in n.frets for _, n in notes)                                    # open strings
    assert any(all(len(n.played) <= 1 for n in s.notes) for s in songs.values())  # single-note melody
    effects = {e for _, n in notes for e in n.effects}
    assert {Effect.HAMMER, Effect.PULL, Effect.SLIDE, Effect.TIE} <= effects
    assert any(n.is_rest for _, n in notes)                                       # an explicit rest (muted chuck)


def test_melodies_by_pitch(songs):
    # MIDI numbers written out by hand: E4=64 F4=65 G4=67 D4=62 C4=60; C3=48 G3=55 A3=57
    ode = [n.pitches for n in songs["ode_to_joy"].notes[:15]]
    assert ode == [(p,) for p in (64, 64, 65, 67, 67, 65, 64, 62, 60, 60, 62, 64, 64, 62, 62)]
    assert [n.duration for n in songs["ode_to_joy"].notes[12:15]] == [F(3, 8), F(1, 8), F(1, 2)]
    tw = [n.pitches for n in songs["twinkle"].notes[:7]]
    assert tw == [(p,) for p in (48, 48, 55, 55, 57, 57, 55)]
    # Romance: B4 (71) over the open low E (40), then the open B (59) and G (55) strings
    assert [n.pitches for n in songs["spanish_romance"].notes[:3]] == [(71, 40), (59,), (55,)]
    assert songs["spanish_romance"].notes[0].duration == F(1, 12)                # a triplet eighth


def test_rising_sun_hints(songs):
    song = songs["rising_sun"]
    am = (0, 1, 2, 2, 0, MUTE)  # x02210, string 1 first
    first_bar = song.notes[:6]
    assert [n.chord for n in first_bar] == [am] * 6
    assert [n.played for n in first_bar] == [(5,), (3,), (2,), (1,), (2,), (3,)]
    assert song.notes[-1].chord == (0, 0, 1, 2, 2, 0)  # E = 022100


def test_load_by_name_and_options():
    song = load_song("ode_to_joy")  # the loader falls back to the embedded library
    assert song.title == "Ode to Joy" and song.tempo == 120
    slow = library.load("ode_to_joy", tempo=60)
    assert slow.tempo == 60 and slow.seconds == pytest.approx(2 * song.seconds)



def tab(path, tempo):
    """A JSON tab of one open high-E quarter note."""
    path.write_text(json.dumps([{"tempo": tempo, "notes": [{"t": "1/4", "frets": [0, -1, -1, -1, -1, -1]}]}]))
    return path


def test_load_songs_files_names_and_folders(tmp_path):
    folder = tmp_path / "set"
    folder.mkdir()
    tab(folder / "b.json", 90), tab(folder / "a.json", 80)
    (folder / "notes.md").write_text("not a tab")           # no reader for .md: skipped
    (folder / "sub.json").mkdir()                           # not a file: skipped, and not searched
    tab(folder / "sub.json" / "c.json", 60)
    songs = load_songs([tab(tmp_path / "one.json", 70), "twinkle", folder])
    assert len(songs) == 4 and songs[1] == library.load("twinkle")
    assert [s.tempo for s in songs[:1] + songs[2:]] == [70, 80, 90]        # the folder's files sorted: a, b
    assert [s.tempo for s in load_songs([folder / "sub.json"])] == [60]     # a folder named like a tab file
    assert load_songs([]) == []


def test_load_songs_errors(tmp_path):
    with pytest.raises(SongError) as info:
        load_songs([tmp_path / "missing.json"])
    assert str(info.value) == f"{tmp_path / 'missing.json'}: no such file, folder or embedded song"
    with pytest.raises(SongError, match=r"^no_such_song: no such file, folder or embedded song$"):
        load_songs(["no_such_song"])
    empty = tmp_path / "x.json"
    empty.mkdir()
    (empty / "readme.md").write_text("")
    with pytest.raises(SongError) as info:
        load_songs([empty])
    assert str(info.value) == (f"{empty}: no tab files (.json, .txt, .tab, .gp3, .gp4, .gp5, .mid, .midi, .musicxml, .mxl) "
                               f"in this folder")
