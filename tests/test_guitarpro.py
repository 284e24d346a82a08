from fractions import Fraction

import guitarpro as gp
import pytest

from dexguitar.music.guitarpro import read_guitarpro
from dexguitar.music.song import MUTE, Effect, Song, SongError, make_note

X = MUTE
N, T, H, P, S = Effect.NONE, Effect.TIE, Effect.HAMMER, Effect.PULL, Effect.SLIDE
STANDARD = [(1, 64), (2, 59), (3, 55), (4, 50), (5, 45), (6, 40)]


def fx(**by_string):
    e = [N] * 6
    for k, v in by_string.items():
        e[int(k[1:]) - 1] = v
    return tuple(e)


def beat(value, notes=(), *, dotted=False, tuplet=(1, 1), rest=False):
    """notes: (string, fret) or (string, fret, kind) with kind in normal/tie/dead/hammer/slide."""
    return dict(value=value, notes=notes, dotted=dotted, tuplet=tuplet, rest=rest)


def fill_track(track, measures):
    for measure, beats in zip(track.measures, measures):
        voice = measure.voices[0]
        for spec in beats:
            b = gp.Beat(voice, duration=gp.Duration(value=spec["value"], isDotted=spec["dotted"],
                                                    tuplet=gp.Tuplet(*spec["tuplet"])),
                        status=gp.BeatStatus.rest if spec["rest"] else gp.BeatStatus.normal)
            for string, fret, *kind in spec["notes"]:
                kind = kind[0] if kind else "normal"
                n = gp.Note(b, value=fret, string=string,
                            type={"tie": gp.NoteType.tie, "dead": gp.NoteType.dead}.get(kind, gp.NoteType.normal))
                if kind == "hammer":
                    n.effect.hammer = True
                if kind == "slide":
                    n.effect.slides = [gp.SlideType.shiftSlideTo]
                b.notes.append(n)
            voice.beats.append(b)


def make_song(measures, *, tempo=96, title="Test", tuning=STANDARD, extra_tracks=(), n_measures=None):
    """A one-guitar-track song; `extra_tracks` = list of (name, strings, percussion) inserted before it."""
    song = gp.Song(title=title, tempo=tempo)
    for _ in range((n_measures or len(measures)) - 1):
        song.newMeasure()
    song.tracks = []
    for i, (name, strings, percussion) in enumerate(extra_tracks):
        t = gp.Track(song, number=i + 1, name=name, isPercussionTrack=percussion,
                     strings=[gp.GuitarString(n, v) for n, v in strings])
        if percussion:
            t.channel = gp.MidiChannel(channel=9, effectChannel=9)
        else:
            t.channel = gp.MidiChannel(channel=2 * i, effectChannel=2 * i + 1)
        song.tracks.append(t)
    guitar = gp.Track(song, number=len(song.tracks) + 1, name="Guitar",
                      strings=[gp.GuitarString(n, v) for n, v in tuning])
    song.tracks.append(guitar)
    fill_track(guitar, measures)
    return song


BASIC = [
    [beat(4, [(3, 0)]),                                  # open G string
     beat(8, [(2, 1), (3, 0), (4, 2), (5, 3)]),          # C major chord
     beat(8, rest=True),                                 # eighth rest
     beat(4, [(1, 5, "hammer")], dotted=True),           # dotted quarter, hammer-on origin
     beat(8, [(1, 7)])],                                 # ... hammered to fret 7
    [beat(8, [(1, 7, "hammer")], tuplet=(3, 2)),         # triplet eighths: pull-off 7 -> 5
     beat(8, [(1, 5)], tuplet=(3, 2)),
     beat(8, [(1, 5, "tie")], tuplet=(3, 2)),            # tied
     beat(4, [(6, 3, "slide")]),                         # slide origin 3 ...
     beat(4, [(6, 5), (2, 0, "dead")]),                  # ... slides to 5; dead note = not played
     beat(4, [(5, 2)])],
]


def expected_basic(title="Test"):
    return Song(tempo=96, title=title, notes=(
        make_note(Fraction(1, 4), (X, X, 0, X, X, X)),
        make_note(Fraction(1, 8), (X, 1, 0, 2, 3, X)),
        make_note(Fraction(1, 8), (X,) * 6),
        make_note(Fraction(3, 8), (5, X, X, X, X, X)),
        make_note(Fraction(1, 8), (7, X, X, X, X, X), fx(s1=H)),
        make_note(Fraction(1, 12), (7, X, X, X, X, X)),
        make_note(Fraction(1, 12), (5, X, X, X, X, X), fx(s1=P)),
        make_note(Fraction(1, 12), (5, X, X, X, X, X), fx(s1=T)),
        make_note(Fraction(1, 4), (X, X, X, X, X, 3)),
        make_note(Fraction(1, 4), (X, X, X, X, X, 5), fx(s6=S)),
        make_note(Fraction(1, 4), (X, X, X, X, 2, X)),
    ))


def test_gp5_basic(tmp_path):
    path = tmp_path / "basic.gp5"
    gp.write(make_song(BASIC), str(path))
    song = read_guitarpro(path)
    assert song == expected_basic()
    assert song.whole_notes == 2  # two 4/4 measures


@pytest.mark.parametrize("suffix", ["gp3", "gp4"])
def test_older_versions(tmp_path, suffix):
    path = tmp_path / f"basic.{suffix}"
    gp.write(make_song(BASIC), str(path))
    assert read_guitarpro(path) == expected_basic()


def test_track_choice_and_empty_measure(tmp_path):
    extra = [("Drums", STANDARD, True), ("Bass", [(1, 43), (2, 38), (3, 33), (4, 28)], False)]
    song = make_song([[beat(2, [(2, 3)]), beat(2, [(2, 5)])]], extra_tracks=extra, n_measures=2, title="")
    path = tmp_path / "band.gp5"
    gp.write(song, str(path))
    got = read_guitarpro(path)
    assert got.title == "band"  # no title in the file: the file name
    # The guitar is picked (track 2); its empty second measure becomes a whole-measure rest.
    assert got.notes == (make_note(Fraction(1, 2), (X, 3, X, X, X, X)), make_note(Fraction(1, 2), (X, 5, X, X, X, X)),
                         make_note(1, (X,) * 6))
    assert read_guitarpro(path, track=2) == got
    with pytest.raises(SongError, match="track 0: 'Drums' is a percussion track"):
        read_guitarpro(path, track=0)
    with pytest.raises(SongError, match="track 1: 'Bass' has 4 strings"):
        read_guitarpro(path, track=1)
    with pytest.raises(SongError, match="track 5 does not exist"):
        read_guitarpro(path, track=5)


def test_other_tuning_rejected(tmp_path):
    drop_d = [(1, 64), (2, 59), (3, 55), (4, 50), (5, 45), (6, 38)]
    path = tmp_path / "dropd.gp5"
    gp.write(make_song([[beat(1, [(6, 0)])]], tuning=drop_d), str(path))
    with pytest.raises(SongError, match=r"dropd\.gp5:track 0: 'Guitar' is tuned E4 B3 G3 D3 A2 D2; only standard"):
        read_guitarpro(path)


def test_no_guitar_track(tmp_path):
    song = make_song([[beat(1, [(1, 0)])]])
    song.tracks[0].strings = [gp.GuitarString(n, v) for n, v in [(1, 43), (2, 38), (3, 33), (4, 28)]]
    path = tmp_path / "bass.gp5"
    gp.write(song, str(path))
    with pytest.raises(SongError, match=r"bass\.gp5: no 6-string guitar track"):
        read_guitarpro(path)


def test_fret_too_high_names_position(tmp_path):
    path = tmp_path / "high.gp5"
    gp.write(make_song([[beat(1, [(1, 12)])], [beat(2, [(1, 12)]), beat(2, [(2, 24)])]]), str(path))
    with pytest.raises(SongError) as info:
        read_guitarpro(path)
    assert info.value.path == path
    assert info.value.where == "track 0, measure 2, beat 2"
    assert "string 2: fret 24 is outside 0..22" in str(info.value)


def test_truncated_and_foreign_files(tmp_path):
    good = tmp_path / "good.gp5"
    gp.write(make_song(BASIC), str(good))
    data = good.read_bytes()
    (tmp_path / "cut10.gp5").write_bytes(data[:10])   # a length byte, then 9 of the 30 bytes of the version
    with pytest.raises(SongError, match=r"cut10\.gp5:byte 10: cannot read as Guitar Pro 3/4/5: unsupported "
                                        r"version 'FICHIER G'"):
        read_guitarpro(tmp_path / "cut10.gp5")
    for n in (len(data) // 2, len(data) - 40):
        bad = tmp_path / f"cut{n}.gp5"
        bad.write_bytes(data[:n])
        with pytest.raises(SongError, match=rf"cut{n}\.gp5:byte {n}: cannot read as Guitar Pro 3/4/5: the file "
                                            rf"ends in the middle of the song data \(truncated\?\)"):
            read_guitarpro(bad)
    text = tmp_path / "notes.gp5"
    text.write_text("this is not a guitar pro file at all")
    # the first byte, 't' = 116, is taken as the length of the 30-byte version string that follows it
    with pytest.raises(SongError, match=r"notes\.gp5:byte 31: cannot read as Guitar Pro 3/4/5: unsupported version "
                                        r"'his is not a guitar pro file a'"):
        read_guitarpro(text)
    with pytest.raises(SongError, match=r"missing\.gp5: no such file"):
        read_guitarpro(tmp_path / "missing.gp5")


def test_tempo_out_of_range(tmp_path):
    path = tmp_path / "fast.gp5"
    gp.write(make_song(BASIC, tempo=500), str(path))
    with pytest.raises(SongError, match=r"fast\.gp5:track 0: tempo 500 BPM is outside 20\.\.400"):
        read_guitarpro(path)
