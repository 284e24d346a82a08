from fractions import Fraction

import mido
import pytest

from dexguitar.music.midi import read_midi
from dexguitar.music.song import MUTE, SongError
from dexguitar.world.guitar import OPEN_MIDI

TPB = 480
C_MAJOR_SCALE = [60, 62, 64, 65, 67, 69, 71, 72]
TRIAD = [60, 64, 67]  # C4 E4 G4


def pitches_of(frets):
    """Sounding pitches computed straight from the open-string table (independent of the reader)."""
    return sorted(OPEN_MIDI[s] + f for s, f in enumerate(frets) if f != MUTE)


def write_midi(path, tracks, *, tempo_bpm=None, time_signature=None, ticks_per_beat=TPB):
    """tracks: lists of (start_tick, length_ticks, pitch[, channel]). A conductor track holds tempo/signature."""
    mid = mido.MidiFile(ticks_per_beat=ticks_per_beat)
    conductor = mido.MidiTrack()
    if tempo_bpm is not None:
        conductor.append(mido.MetaMessage("set_tempo", tempo=mido.bpm2tempo(tempo_bpm), time=0))
    if time_signature is not None:
        conductor.append(mido.MetaMessage("time_signature", numerator=time_signature[0],
                                          denominator=time_signature[1], time=0))
    mid.tracks.append(conductor)
    for notes in tracks:
        events = []
        for start, length, pitch, *channel in notes:
            ch = channel[0] if channel else 0
            events.append((start, 1, mido.Message("note_on", note=pitch, velocity=80, channel=ch)))
            events.append((start + length, 0, mido.Message("note_off", note=pitch, velocity=0, channel=ch)))
        events.sort(key=lambda e: (e[0], e[1]))
        track, now = mido.MidiTrack(), 0
        for tick, _, msg in events:
            track.append(msg.copy(time=tick - now))
            now = tick
        mid.tracks.append(track)
    mid.save(str(path))
    return path


def test_scale_and_triad(tmp_path):
    notes = [(i * TPB, TPB, p) for i, p in enumerate(C_MAJOR_SCALE)]
    notes += [(8 * TPB, 2 * TPB, p) for p in TRIAD]
    notes += [(0, TPB, 36, 9), (4 * TPB, TPB, 38, 9)]  # drums on channel 10: ignored
    path = write_midi(tmp_path / "scale.mid", [notes], tempo_bpm=100)
    song = read_midi(path)
    assert song.tempo == pytest.approx(100)
    assert song.title == "scale"
    assert len(song.notes) == 9
    for n, p in zip(song.notes[:8], C_MAJOR_SCALE):
        assert pitches_of(n.frets) == [p]
        assert n.duration == Fraction(1, 4)
    triad = song.notes[8]
    assert pitches_of(triad.frets) == TRIAD
    pressed = [f for f in triad.frets if f > 0]
    assert max(pressed) - min(pressed) <= 3  # fits under four fingers
    assert triad.duration == Fraction(1, 2)  # last note: its own length
    assert song.whole_notes == Fraction(5, 2)


def test_quantization_triplets_and_rests(tmp_path):
    third = TPB // 3  # triplet eighth
    notes = [(0 + 7, third, 64), (third - 5, third, 65), (2 * third, third, 67),   # jittered triplets
             (TPB, TPB // 4, 69),                                              # a sixteenth ...
             (3 * TPB, TPB, 71), (3 * TPB + 3, TPB, 74)]                       # ... a long gap, then a chord
    path = write_midi(tmp_path / "trip.mid", [notes])
    song = read_midi(path, grid="1/48")
    assert song.tempo == 120  # no set_tempo: default
    durations = [n.duration for n in song.notes]
    assert durations == [Fraction(1, 12)] * 3 + [Fraction(1, 16), Fraction(7, 16), Fraction(1, 4)]
    assert song.notes[4].is_rest  # the 7/16 gap after the sixteenth
    assert [pitches_of(n.frets) for n in song.notes] == [[64], [65], [67], [69], [], [71, 74]]
    # A triplet grid snaps the same jittered onsets.
    song12 = read_midi(path, grid="1/12")
    assert [n.duration for n in song12.notes[:3]] == [Fraction(1, 12)] * 3


def test_gap_of_one_step_is_absorbed(tmp_path):
    # Staccato eighths (a sixteenth long, then a sixteenth of silence): no rests on a 1/16 grid.
    notes = [(i * TPB // 2, TPB // 4, 64 + i) for i in range(4)]
    song = read_midi(write_midi(tmp_path / "stacc.mid", [notes]))
    assert [n.duration for n in song.notes] == [Fraction(1, 8)] * 3 + [Fraction(1, 16)]
    assert not any(n.is_rest for n in song.notes)


def test_track_selection_and_tempo_option(tmp_path):
    melody = [(0, TPB, 72), (TPB, TPB, 74)]
    bass = [(0, 2 * TPB, 45)]  # open A string under the melody
    path = write_midi(tmp_path / "two.mid", [melody, bass], tempo_bpm=90)
    merged = read_midi(path)
    assert [pitches_of(n.frets) for n in merged.notes] == [[45, 72], [74]]
    assert merged.tempo == pytest.approx(90)
    only_bass = read_midi(path, track=2, tempo=140)
    assert only_bass.tempo == 140
    assert [pitches_of(n.frets) for n in only_bass.notes] == [[45]]
    assert only_bass.notes[0].duration == Fraction(1, 2)
    with pytest.raises(SongError, match="track 0: no notes"):
        read_midi(path, track=0)  # the conductor track
    with pytest.raises(SongError, match="track 7 does not exist"):
        read_midi(path, track=7)


def test_not_a_midi_file(tmp_path):
    path = tmp_path / "fake.mid"
    path.write_text("MThd? no, just text")
    # "MThd" then "? no" read as the header length (big-endian 0x3f206e6f): the 19-byte file ends inside it
    with pytest.raises(SongError, match=r"fake\.mid:byte 19: cannot read as a MIDI file: it ends in the middle"
                       ) as info:
        read_midi(path)
    assert info.value.path == path
    good = write_midi(tmp_path / "good.mid", [[(0, TPB, 60)] * 1])
    cut = tmp_path / "cut.mid"
    cut.write_bytes(good.read_bytes()[:20])
    with pytest.raises(SongError, match=r"cut\.mid:byte 20: cannot read as a MIDI file: it ends in the middle"):
        read_midi(cut)


def test_only_drums_means_no_notes(tmp_path):
    path = write_midi(tmp_path / "drums.mid", [[(0, TPB, 36, 9)]])
    with pytest.raises(SongError, match=r"drums\.mid: no notes"):
        read_midi(path)


def test_unplayable_pitch_names_tick_and_bar(tmp_path):
    notes = [(0, TPB, 60), (TPB, TPB, 62), (7 * TPB, TPB, 24)]  # C1 is below the low E string
    path = write_midi(tmp_path / "low.mid", [notes], time_signature=(3, 4))
    with pytest.raises(SongError) as info:
        read_midi(path)
    assert info.value.where == f"tick {7 * TPB}, bar 3"  # 3/4: bars start at ticks 0, 1440, 2880
    assert "C1 (24)" in str(info.value) and "low.mid" in str(info.value)
    chord7 = [(0, TPB, p) for p in (40, 45, 50, 55, 59, 64, 69)]
    with pytest.raises(SongError, match=r"tick 0, bar 1: chord 0 .*7 notes"):
        read_midi(write_midi(tmp_path / "seven.mid", [chord7]))


def test_bad_options(tmp_path):
    path = write_midi(tmp_path / "ok.mid", [[(0, TPB, 60)]])
    with pytest.raises(SongError, match="grid"):
        read_midi(path, grid="sixteenth")
    with pytest.raises(SongError, match="tempo"):
        read_midi(path, tempo=-1)
    assert read_midi(path, grid="16").notes[0].duration == Fraction(1, 4)


def test_tempo_and_durations_out_of_range(tmp_path):
    # 6,000,000 us per beat = 10 BPM, below 20; the set_tempo event is at tick 0, in bar 1
    slow = write_midi(tmp_path / "slow.mid", [[(0, TPB, 60)]], tempo_bpm=10)
    with pytest.raises(SongError, match=r"slow\.mid:tick 0, bar 1: tempo 10 BPM is outside 20\.\.400"):
        read_midi(slow)
    with pytest.raises(SongError, match=r"slow\.mid: tempo option: tempo 1000 BPM is outside 20\.\.400"):
        read_midi(slow, tempo=1000)
    # a 1/1024 grid at 120 BPM: one step lasts 14400 / 120 / 1024 = 0.12 frames, so a one-step note is refused
    blip = write_midi(tmp_path / "blip.mid", [[(0, 1, 60)]])
    with pytest.raises(SongError, match=r"blip\.mid:note 0: this note \(duration 1/1024\) lasts 0\.12 frames"):
        read_midi(blip, grid="1/1024")
