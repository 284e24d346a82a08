import json
from fractions import Fraction
from pathlib import Path

import pytest

from dexguitar.music.song import MUTE, Effect, Song, SongError, make_note
from dexguitar.music.tab_json import read_json_tab, write_json_tab

OFFICIAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "official" / "notes"
needs_official = pytest.mark.skipif(not OFFICIAL.is_dir(), reason="the authors' official tabs are not here: "
                                   "../shared/data/official/notes/ beside the clone")
OFFICIAL_NAMES = ["beethoven_virus", "canon_in_d_major1", "canon_in_d_major2", "capriccio_op59_no16",
                  "come_as_you_are", "dont_cry", "flight_of_the_bumblebee1", "johnny_b_goodie",
                  "prelude1_in_c_major_chords", "snow", "sonata_in_f_major_ms84_no14", "spring_overture",
                  "super_mario", "turkish_march", "wipe_out"]

N, T, H, P, S = Effect.NONE, Effect.TIE, Effect.HAMMER, Effect.PULL, Effect.SLIDE
X = MUTE


def fx(**by_string):
    """Effects tuple from {"s3": Effect}: string numbers 1..6."""
    e = [N] * 6
    for k, v in by_string.items():
        e[int(k[1:]) - 1] = v
    return tuple(e)


def note(t, frets, effects=None):
    return {"t": t, "effects": effects or {}, "frets": frets}


def write_tracks(path, tracks):
    path.write_text(json.dumps(tracks, indent=1))
    return path


SMALL = [{"tempo": 90, "notes": [
    note("1/8", [X, X, 5, X, X, X]),
    note("1/8", [X, X, 7, X, X, X], {"hammer/pull": [0, 0, 1, 0, 0, 0]}),
    note("1/4", [X, X, 7, X, X, X], {"tied": [0, 0, 1, 0, 0, 0]}),
    note("0.3333333/8", [X, X, 5, X, X, X], {"hammer/pull": [0, 0, 1, 0, 0, 0]}),
    note("0.3333333/8", [X, X, X, 7, X, X]),
    note("0.3333333/8", [0, X, X, X, X, X], {"hammer/pull": [1, 0, 0, 0, 0, 0]}),  # never played before: pull
    note("1/16", [X, X, X, X, 3, X], {"chords": [0, 1, 0, 2, 3, -1]}),
    note("1/16", [X, 1, X, X, X, X], {"chords": [0, 1, 0, 2, 3, -1]}),
    note("1", [X, X, X, X, X, X]),
    note(0.25, [0, 0, 1, 2, 2, 0]),
    note("3/16", [X, X, X, X, X, 3]),
]}]


def expected_small(title):
    c = (0, 1, 0, 2, 3, -1)
    return Song(tempo=90, title=title, notes=(
        make_note(Fraction(1, 8), (X, X, 5, X, X, X)),
        make_note(Fraction(1, 8), (X, X, 7, X, X, X), fx(s3=H)),
        make_note(Fraction(1, 4), (X, X, 7, X, X, X), fx(s3=T)),
        make_note(Fraction(1, 24), (X, X, 5, X, X, X), fx(s3=P)),
        make_note(Fraction(1, 24), (X, X, X, 7, X, X)),
        make_note(Fraction(1, 24), (0, X, X, X, X, X), fx(s1=P)),
        make_note(Fraction(1, 16), (X, X, X, X, 3, X), chord=c),
        make_note(Fraction(1, 16), (X, 1, X, X, X, X), chord=c),
        make_note(Fraction(1), (X,) * 6),
        make_note(Fraction(1, 4), (0, 0, 1, 2, 2, 0)),
        make_note(Fraction(3, 16), (X, X, X, X, X, 3)),
    ))


def test_small_file_exact(tmp_path):
    path = write_tracks(tmp_path / "small.json", SMALL)
    song = read_json_tab(path)
    assert song == expected_small("small")
    assert song.notes[3].duration == Fraction(1, 24)  # "0.3333333/8" snapped to the exact triplet eighth
    assert song.notes[8].is_rest


def test_second_track_and_title(tmp_path):
    tracks = SMALL + [{"tempo": 60, "title": "B side", "notes": [note("2", [X, X, X, X, X, 0])]}]
    path = write_tracks(tmp_path / "two.json", tracks)
    song = read_json_tab(path, track=1)
    assert song.tempo == 60 and song.title == "B side"
    assert song.notes == (make_note(2, (X, X, X, X, X, 0)),)


def test_round_trip(tmp_path):
    song = Song(tempo=97.5, title="rt", notes=(
        make_note(Fraction(1, 12), (X, 3, X, X, X, X)),
        make_note(Fraction(1, 12), (X, 5, X, X, X, X), fx(s2=H)),
        make_note(Fraction(1, 12), (X, 3, X, X, X, X), fx(s2=P)),
        make_note(Fraction(3, 32), (X, 3, X, X, 2, X), fx(s2=T)),
        make_note(Fraction(1, 4), (X, X, X, X, 4, X), fx(s5=S)),     # slide: written as hammer/pull
        make_note(Fraction(2), (X,) * 6),
        make_note(Fraction(1, 16), (X, X, X, 2, X, X), chord=(0, 1, 0, 2, 3, -1)),
    ))
    path = tmp_path / "rt.json"
    write_json_tab(song, path)
    back = read_json_tab(path)
    slide_as_hammer = list(song.notes)
    slide_as_hammer[4] = make_note(Fraction(1, 4), (X, X, X, X, 4, X), fx(s5=H))  # 4 > 2: a hammer-on
    assert back == song.replace(notes=tuple(slide_as_hammer))
    data = json.loads(path.read_text())
    assert [n["t"] for n in data[0]["notes"]] == ["1/12", "1/12", "1/12", "3/32", "1/4", "2/1", "1/16"]
    assert data[0]["notes"][4]["effects"] == {"hammer/pull": [0, 0, 0, 0, 1, 0]}
    assert data[0]["notes"][6]["effects"] == {"chords": [0, 1, 0, 2, 3, -1]}
    # And a song without slides comes back identical.
    small = read_json_tab(write_tracks(tmp_path / "small.json", SMALL))
    write_json_tab(small, tmp_path / "again.json")
    assert read_json_tab(tmp_path / "again.json") == small


@needs_official
@pytest.mark.parametrize("name", OFFICIAL_NAMES)
def test_official_files_load_and_round_trip(name, tmp_path):
    song = read_json_tab(OFFICIAL / f"{name}.json")
    raw = json.loads((OFFICIAL / f"{name}.json").read_text())[0]
    assert song.tempo == raw["tempo"] and len(song.notes) == len(raw["notes"])
    assert all(n.frets == tuple(r["frets"]) for n, r in zip(song.notes, raw["notes"]))
    write_json_tab(song, tmp_path / "copy.json")
    assert read_json_tab(tmp_path / "copy.json") == song


@needs_official
def test_all_fifteen_official_files_present():
    assert sorted(p.stem for p in OFFICIAL.glob("*.json")) == OFFICIAL_NAMES


@needs_official
def test_snow_hand_read():
    song = read_json_tab(OFFICIAL / "snow.json")
    assert song.tempo == 100 and song.title == "snow" and len(song.notes) == 200
    first = song.notes[:8]
    assert [n.duration for n in first] == [Fraction(1, 16)] * 4 + [Fraction(1, 24)] * 3 + [Fraction(1, 16)]
    assert [n.frets for n in first] == [
        (X, X, X, X, 6, X), (X, X, X, 6, X, X), (X, X, 4, X, X, X), (X, X, X, 6, X, X),
        (X, X, 4, X, X, X), (X, X, 6, X, X, X), (X, X, 4, X, X, X), (X, X, X, 6, X, X)]
    assert first[5].effects == fx(s3=H)   # 4 -> 6 on the G string: hammer-on
    assert first[6].effects == fx(s3=P)   # 6 -> 4: pull-off
    assert all(n.effects == fx() for i, n in enumerate(first) if i not in (5, 6))


@pytest.mark.parametrize("tracks, where, message", [
    ([{"tempo": 90}], "track 0", "missing key 'notes'"),
    ([{"notes": []}], "track 0", "missing key 'tempo'"),
    ([{"tempo": 90, "notes": []}], "track 0", "'notes' is empty"),
    ([{"tempo": -5, "notes": [note("1/4", [0] * 6)]}], "track 0", "'tempo': tempo -5 BPM is outside 20..400"),
    ([{"tempo": "fast", "notes": [note("1/4", [0] * 6)]}], "track 0", "'tempo' must be a number"),
    ([{"tempo": 401, "notes": [note("1/4", [0] * 6)]}], "track 0", "'tempo': tempo 401 BPM is outside 20..400"),
    # 1/256 at 60 BPM: 14400 / 60 / 256 = 0.94 frames, under one frame
    ([{"tempo": 60, "notes": [note("1/4", [0] * 6), note("1/256", [0] * 6)]}], "track 0, note 1",
     "this note (duration 1/256) lasts 0.94 frames at 60 BPM"),
    ([{"tempo": 90, "notes": [note("1/4", [0] * 6), note("1/4", [0] * 5)]}], "track 0, note 1",
     "'frets' must be 6 integers"),
    ([{"tempo": 90, "notes": [note("1/4", [0, 0, 0, 0, 0, "3"])]}], "track 0, note 0", "'frets' must be 6 integers"),
    ([{"tempo": 90, "notes": [note("1/4", [0, 0, 23, 0, 0, 0])]}], "track 0, note 0", "string 3: 23 is outside"),
    ([{"tempo": 90, "notes": [note("1/4", [0, -2, 0, 0, 0, 0])]}], "track 0, note 0", "string 2: -2 is outside"),
    ([{"tempo": 90, "notes": [note("x/4", [0] * 6)]}], "track 0, note 0", "'t' must look like"),
    ([{"tempo": 90, "notes": [note("1/0", [0] * 6)]}], "track 0, note 0", "zero denominator"),
    ([{"tempo": 90, "notes": [note("0/4", [0] * 6)]}], "track 0, note 0", "'t' must be positive"),
    ([{"tempo": 90, "notes": [note("0.123/8", [0] * 6)]}], "track 0, note 0", "not close to a fraction"),
    ([{"tempo": 90, "notes": [note([1, 4], [0] * 6)]}], "track 0, note 0", "'t' must be a string or a number"),
    ([{"tempo": 90, "notes": [{"t": "1/4"}]}], "track 0, note 0", "missing key 'frets'"),
    ([{"tempo": 90, "notes": [note("1/4", [0] * 6, {"slide": [0] * 6})]}], "track 0, note 0", "unknown effect"),
    ([{"tempo": 90, "notes": [note("1/4", [0] * 6, {"tied": [0, 0, 2, 0, 0, 0]})]}], "track 0, note 0",
     "'tied' must be 6 values 0 or 1"),
    ([{"tempo": 90, "notes": [note("1/4", [X, 0, 0, 0, 0, 0], {"tied": [1, 0, 0, 0, 0, 0]})]}], "track 0, note 0",
     "marks string 1, which the note does not play"),
    ([{"tempo": 90, "notes": [note("1/4", [0] * 6, {"chords": [0, 1, 2]})]}], "track 0, note 0",
     "'chords' must be 6 integers"),
])
def test_bad_content(tmp_path, tracks, where, message):
    path = write_tracks(tmp_path / "bad.json", tracks)
    with pytest.raises(SongError) as info:
        read_json_tab(path)
    text = str(info.value)
    assert str(path) in text and f":{where}:" in text and message in text, text
    assert info.value.path == path and info.value.where == where


def test_bad_fret_message_names_file_and_note(tmp_path):
    tracks = [{"tempo": 90, "notes": [note("1/4", [0] * 6)] * 17 + [note("1/4", [0, 0, 0, 0, 0, 30])]}]
    path = write_tracks(tmp_path / "fret.json", tracks)
    with pytest.raises(SongError, match=r"fret\.json:track 0, note 17: 'frets' string 6: 30 is outside"):
        read_json_tab(path)


def test_not_json_reports_line_and_column(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('[\n  {"tempo": 90,\n   "notes": [}\n]\n')
    with pytest.raises(SongError, match=r"broken\.json:line 3, column 14: not valid JSON") as info:
        read_json_tab(path)
    assert info.value.where == "line 3, column 14"


def test_bad_top_level_and_track(tmp_path):
    with pytest.raises(SongError, match="expected a list of tracks"):
        read_json_tab(write_tracks(tmp_path / "a.json", "hello"))
    with pytest.raises(SongError, match="no tracks"):
        read_json_tab(write_tracks(tmp_path / "b.json", []))
    with pytest.raises(SongError, match="track 3 does not exist"):
        read_json_tab(write_tracks(tmp_path / "c.json", SMALL), track=3)
    with pytest.raises(SongError, match=r"missing\.json: no such file"):
        read_json_tab(tmp_path / "missing.json")
    latin1 = tmp_path / "latin1.json"
    latin1.write_bytes('[{"title": "Caf\xe9"}]'.encode("latin-1"))    # e-acute is byte 15, one byte in Latin-1
    with pytest.raises(SongError, match=r"latin1\.json:byte 15: not UTF-8 text"):
        read_json_tab(latin1)
