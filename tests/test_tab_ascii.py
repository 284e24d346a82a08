"""ASCII tab reader: expected notes worked out by hand from the tab text."""
from fractions import Fraction as F

import numpy as np
import pytest

from dexguitar.music import load_song
from dexguitar.music.song import MUTE, Effect, SongError
from dexguitar.music.tab_ascii import parse_ascii_tab, read_ascii_tab
from dexguitar.music.timeline import from_song

N, H, P, S, T = Effect.NONE, Effect.HAMMER, Effect.PULL, Effect.SLIDE, Effect.TIE
X = MUTE

# Two systems with text between them; a C chord column, a two-digit fret, 12h14, bar lines (also '||'), a tie,
# an x-only rest column, unlabelled string lines in the second system.
SAMPLE = """\
title: Little Sample
tempo: 90
grid: 1/8

[Intro]  (played once)
e|0---|--12h14-||
B|1---|--------||
G|0---|--------||
D|2---|--------||
A|3---|--------||
E|----|--------||

la la la, some lyrics
|(14)-|---x|
|-----|0---|
|-----|----|
|-----|----|
|-----|----|
|-----|----|
"""
# grid columns: system 1 = 4 + 8 = 12 (C chord at 0, 12 at 6, 14 at 9); system 2 = 5 + 4 = 9, starting at 12:
# tie (14) at 12, B0 at 17, rest at 20, end at 21.
SAMPLE_NOTES = [  # (duration in columns, frets string 1..6, effects)
    (6, (0, 1, 0, 2, 3, X), (N,) * 6),
    (3, (12, X, X, X, X, X), (N,) * 6),
    (3, (14, X, X, X, X, X), (H, N, N, N, N, N)),
    (5, (14, X, X, X, X, X), (T, N, N, N, N, N)),
    (3, (X, 0, X, X, X, X), (N,) * 6),
    (1, (X,) * 6, (N,) * 6),
]


def check_notes(song, expected, grid):
    assert len(song.notes) == len(expected)
    for note, (cols, frets, effects) in zip(song.notes, expected):
        assert note.duration == cols * grid
        assert note.frets == frets
        assert note.effects == effects
        assert note.chord is None


def test_sample_from_header():
    song = parse_ascii_tab(SAMPLE)
    assert song.title == "Little Sample"
    assert song.tempo == 90
    check_notes(song, SAMPLE_NOTES, F(1, 8))
    assert song.whole_notes == F(21, 8)
    assert song.seconds == pytest.approx(7.0)          # 21/8 whole = 10.5 beats at 90 BPM
    assert song.notes[0].pitches == (64, 60, 55, 52, 48)  # C major: E4 C4 G3 E3 C3
    assert song.notes[-1].is_rest and song.n_notes == 5 and song.n_chords == 1
    assert song.notes[3].picked == (False,) * 6 and song.notes[1].picked[0]


def test_options_override_header(tmp_path):
    f = tmp_path / "sample.txt"
    f.write_text(SAMPLE)
    song = read_ascii_tab(f, tempo=60, grid="1/16", title="Other")
    assert (song.tempo, song.title) == (60, "Other")
    check_notes(song, SAMPLE_NOTES, F(1, 16))
    assert song.seconds == pytest.approx(21 / 16 * 4)  # 21/16 whole notes at 60 BPM
    assert read_ascii_tab(f, grid=F(1, 4)).notes[0].duration == F(6, 4)
    assert read_ascii_tab(f, grid=4).notes[0].duration == F(6, 4)    # an integer n means 1/n
    assert load_song(f).notes[0].duration == F(6, 8)                  # loader dispatch on .txt


def test_defaults_and_title_from_file_stem(tmp_path):
    f = tmp_path / "my_riff.tab"
    f.write_text("e|-0-5-|\nB|-----|\nG|-----|\nD|-----|\nA|-----|\nE|-----|\n")
    song = load_song(f)
    assert song.title == "my_riff" and song.tempo == 120
    # default grid 1/16; a leading '-' before the first onset is a rest
    assert [n.duration for n in song.notes] == [F(1, 16), F(2, 16), F(2, 16)]
    assert [n.frets[0] for n in song.notes] == [X, 0, 5] and song.notes[0].is_rest
    assert parse_ascii_tab(f.read_text()).title == ""


@pytest.mark.parametrize("tempo_line, grid_line, tempo, grid", [
    ("bpm = 100", "grid = 1/4", 100, F(1, 4)),
    ("Tempo 72", "Grid 8", 72, F(1, 8)),
    ("TEMPO: 150 bpm", "grid: 0.125", 150, F(1, 8)),
])
def test_header_spellings(tempo_line, grid_line, tempo, grid):
    text = f"{tempo_line}\n{grid_line}\n" + "|0-|\n" * 6
    song = parse_ascii_tab(text)
    assert song.tempo == tempo
    assert song.notes[0].duration == 2 * grid and song.notes[0].frets == (0,) * 6


def test_effects_and_marks():
    text = """\
E|5h7p5-3/5\\3--5-~~|
B|-------------5---|
G|-------------5---|
D|-------------x---|
A|-----------------|
E|0s2--------------|
"""
    # columns: 5@0 h 7@2 p 5@4 - 3@6 / 5@8 \ 3@10 -- 5@13 (+B5, G5; the D string's x = not played) ~~
    # low E: 0@0 s 2@2
    song = parse_ascii_tab(text)
    assert [(n.duration * 16, n.frets, n.effects) for n in song.notes] == [
        (2, (5, X, X, X, X, 0), (N,) * 6),
        (2, (7, X, X, X, X, 2), (H, N, N, N, N, S)),
        (2, (5, X, X, X, X, X), (P, N, N, N, N, N)),
        (2, (3, X, X, X, X, X), (N,) * 6),
        (2, (5, X, X, X, X, X), (S, N, N, N, N, N)),
        (3, (3, X, X, X, X, X), (S, N, N, N, N, N)),
        (4, (5, 5, 5, X, X, X), (N,) * 6),
    ]


def test_chord_hints():
    text = """\
chord Am = x02210
chord: E7 = 0, 2, 0, 1, 3, 0
chords: Am E7      -
e|0-------|0-------|0-------|
B|1-------|3-------|--------|
G|2-------|1-------|--------|
D|2---2---|0-------|--------|
A|0-------|2-------|--------|
E|--------|0-------|--------|

|0---|
|----|
|----|
|----|
|----|
|----|
"""
    am, e7 = (0, 1, 2, 2, 0, X), (0, 3, 1, 0, 2, 0)   # string 1 first: chord notation reversed
    song = parse_ascii_tab(text)
    assert [n.frets for n in song.notes] == [am, (X, X, X, 2, X, X), e7, (0, X, X, X, X, X), (0, X, X, X, X, X)]
    # 'Am' (first name) holds from the system start, 'E7' starts under its first letter (bar 2), '-' over the
    # bar line ends the hint from the next column on; the next system keeps "no hint"
    assert [n.chord for n in song.notes] == [am, am, e7, None, None]
    assert [n.duration for n in song.notes] == [F(4, 16), F(4, 16), F(8, 16), F(8, 16), F(4, 16)]
    # without the '-' the E7 hint holds into the following system
    song = parse_ascii_tab(text.replace("E7      -", "E7"))
    assert [n.chord for n in song.notes] == [am, am, e7, e7, e7]


def test_web_paste_layout():
    text = """\
Some Song - tabbed by someone
Tuning: standard        ----------------------

[Verse]
E |-0--2--|-3---------|  x2
B |-------|-----------|
G |-------|-----------|
D |-------|-----------|
A |-------|-----------|
E |-------|-----------|
e|-12~~--|-(12)-|
b|--x----|----12|
g|-------|------|
d|-------|------|
a|-------|------|
e|-------|------|
--------------------------------
"""
    song = parse_ascii_tab(text)  # labels 'E |', 12 lines = two systems back to back, trailing "x2" ignored
    assert [(n.duration * 16, n.frets[:2], n.effects[0]) for n in song.notes] == [
        (1, (X, X), N), (3, (0, X), N), (4, (2, X), N), (11, (3, X), N),
        (7, (12, X), N), (3, (12, X), T), (2, (X, 12), N)]


@pytest.mark.parametrize("text, line, fragment", [
    ("title: t\ne|--0--|\nB|-----|\nG|-----|\nD|-----|\nA|-----|\n", 2, "found 5"),
    ("e|--25--|\nB|------|\nG|------|\nD|------|\nA|------|\nE|------|\n", 1, "fret 25"),
    ("e|------|\nB|------|\nG|--q---|\nD|------|\nA|------|\nE|------|\n", 3, "unknown character 'q'"),
    ("e|------|\nB|--5h--|\nG|------|\nD|------|\nA|------|\nE|------|\n", 2, "right after"),
    ("\ne|------|\nB|------|\nG|------|\nD|------|\nA|--h5--|\nE|------|\n", 6, "right before"),
    ("e|--3---|\nB|------|\nG|------|\nD|---|--|\nA|------|\nE|------|\n", 4, "bar line"),
    ("e|--3---|\nB|------|\nG|------|\nD|------|\nA|------|\nE|-----|\n", 6, "same length"),
    ("x\nchord C = x32010\nchords: Am\ne|0--|\nB|---|\nG|---|\nD|---|\nA|---|\nE|---|\n", 3, "'Am' is not defined"),
    ("title: t\ntempo: fast\n" + "|0-|\n" * 6, 2, "malformed tempo"),
    ("grid: 1/0\n" + "|0-|\n" * 6, 1, "malformed grid"),
    ("\n\nchord Am = x0221\n" + "|0-|\n" * 6, 3, "6 entries"),
    ("tempo: 90\n\nbpm: 80\n" + "|0-|\n" * 6, 3, "tempo is given twice"),
    ("e|3-(5)|\nB|-----|\nG|-----|\nD|-----|\nA|-----|\nE|-----|\n", 1, "tie (5)"),
    ("e|------|\nB|-123--|\nG|------|\nD|------|\nA|------|\nE|------|\n", 2, "more than two digits"),
    ("e|-----|\nB|-----|\nG|-7h5-|\nD|-----|\nA|-----|\nE|-----|\n", 3, "higher fret"),
    ("E|---|\nA|---|\nD|---|\nG|---|\nB|---|\ne|-0-|\n", 2, "standard tuning"),
    ("e|---|\nB|---|\nG|---|\nD|---|\nA|---|\nE|-x-|\n", 1, "no notes"),
])
def test_malformed_input_names_file_and_line(tmp_path, text, line, fragment):
    f = tmp_path / "bad_song.txt"
    f.write_text(text)
    with pytest.raises(SongError) as info:
        read_ascii_tab(f)
    message = str(info.value)
    assert "bad_song.txt" in message
    assert f"line {line}" in message
    assert fragment in message


def test_tie_across_bars_into_a_long_note():
    text = """\
tempo: 60
e|0---------------|(0)-------------|----------------|
B|----------------|----------------|----------------|
G|----------------|----------------|----------------|
D|----------------|----------------|----------------|
A|----------------|----------------|----------------|
E|----------------|----------------|----------------|
"""
    # 16 columns of 1/16 per bar: the open E lasts bar 1 (1 whole note), the tie from its '(' to the end (2 bars)
    song = parse_ascii_tab(text)
    assert [(n.duration, n.frets[0], n.effects[0]) for n in song.notes] == [(1, 0, N), (2, 0, T)]
    # at 60 BPM a whole note is 4 s = 240 frames
    assert np.asarray(from_song(song).onset).tolist() == [0, 240, 720]


@pytest.mark.parametrize("header, where, fragment", [
    ("tempo: 1000", "line 1, column 8", "tempo 1000 BPM is outside 20..400"),
    # 1/512 at 120 BPM: 14400 / 120 / 512 = 0.23 frames, under one frame
    ("grid: 1/512", "note 0", "this note (duration 1/512) lasts 0.23 frames at 120 BPM"),
])
def test_absurd_tempo_and_grid(header, where, fragment):
    with pytest.raises(SongError) as info:
        parse_ascii_tab(header + "\n" + "e|0|\nB|-|\nG|-|\nD|-|\nA|-|\nE|-|\n", path="odd.txt")
    assert info.value.where == where and fragment in str(info.value)


def test_error_column_and_no_systems():
    with pytest.raises(SongError, match=r"<input>:line 3, column 6: fret 23"):
        parse_ascii_tab("\n\ne|---23-|\nB|------|\nG|------|\nD|------|\nA|------|\nE|------|\n")
    with pytest.raises(SongError, match=r"x\.txt: no tab systems"):
        parse_ascii_tab("title: nothing here\njust words\n", path="x.txt")
    with pytest.raises(SongError, match="no such file"):
        read_ascii_tab("/nonexistent/dir/song.txt")
    with pytest.raises(SongError, match="tempo option"):
        parse_ascii_tab("|0-|\n" * 6, tempo=0)
    with pytest.raises(SongError, match="grid option"):
        parse_ascii_tab("|0-|\n" * 6, grid="sixteenth")


def test_text_that_looks_like_tab_is_skipped():
    text = """\
A-men
- a list item
---- Chorus ----
| Am | C | G |
-----------
e|0|
B|-|
G|-|
D|-|
A|-|
E|-|
"""
    song = parse_ascii_tab(text)
    assert [(n.duration, n.frets) for n in song.notes] == [(F(1, 16), (0, X, X, X, X, X))]
