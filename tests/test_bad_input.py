"""Issue #14, input handling: every bad file a user can hand us raises an `InputError` (a `UserError` the CLI prints
as one line) naming the file and the position, and valid but unusual songs work. Every input is made here; every
expected number is worked out by hand in the comments."""
import gzip
import json
import time
from fractions import Fraction as F

import mido
import numpy as np
import pytest

from dexguitar.errors import InputError, UserError
from dexguitar.motion import load_motion
from dexguitar.motion.format import Motion, MotionError, joint_ranges, save
from dexguitar.motion.official import read_official_json
from dexguitar.motion.retarget import RetargetError, read_markers
from dexguitar.music import load_song
from dexguitar.music.song import MUTE as X, Song, SongError, make_note
from dexguitar.music.tab_ascii import parse_ascii_tab
from dexguitar.music.tab_json import write_json_tab
from dexguitar.music.timeline import from_song
from dexguitar.world import hands as H

SYSTEM = "e|0---|\nB|----|\nG|----|\nD|----|\nA|----|\nE|----|\n"   # one open high E, a quarter note


def json_tab(path, tempo, durations):
    path.write_text(json.dumps([{"tempo": tempo, "notes": [{"t": t, "frets": [0, X, X, X, X, X]}
                                                           for t in durations]}]))
    return path


def error_of(fn, *args, kind=InputError):
    with pytest.raises(kind) as info:
        fn(*args)
    assert isinstance(info.value, UserError)
    return info.value


# ------------------------------------------------------------------------------------------------ song timing

def test_long_notes_through_every_stage(tmp_path):
    # 2, 2 and 4 whole notes at 90 BPM: a whole note is 4 beats of 2/3 s = 8/3 s = 160 frames, so 320, 320, 640
    # frames; the shortest note (2 whole) is 320 frames exactly, so the tempo stays 90.
    song = load_song(json_tab(tmp_path / "long.json", 90, ["2", "2", "4"]))
    tl = from_song(song)
    assert np.asarray(tl.onset).tolist() == [0, 320, 640, 1280]
    assert float(tl.tempo) == 90


def test_absurd_durations_and_tempos_are_refused(tmp_path):
    # 1/100000 at 120 BPM: 14400 / 120 = 120 frames per whole note, so 120 / 100000 = 0.0012 frames; a note needs at
    # least one frame, i.e. 1/120 of a whole note at 120 BPM.
    e = error_of(load_song, json_tab(tmp_path / "fine.json", 120, ["1/4", "1/100000"]), kind=SongError)
    assert e.where == "track 0, note 1"
    assert "duration 1/100000) lasts 0.0012 frames at 120 BPM" in str(e) and "1/120 of a whole note" in str(e)
    e = error_of(load_song, json_tab(tmp_path / "fast.json", 1e9, ["1/4"]), kind=SongError)
    assert str(e).endswith("fast.json:track 0: 'tempo': tempo 1e+09 BPM is outside 20..400 (quarter-note beats per "
                           "minute)")
    path = tmp_path / "slow.txt"
    path.write_text("title: slow\ntempo: 10\n" + SYSTEM)
    e = error_of(load_song, path, kind=SongError)
    assert e.where == "line 2, column 8" and "tempo 10 BPM is outside 20..400" in str(e)
    # 1000 whole notes at 120 BPM = 1000 * 120 = 120000 frames, past 30 min * 60 s * 60 Hz = 108000
    e = error_of(load_song, json_tab(tmp_path / "drone.json", 120, ["1/4", "1000"]), kind=SongError)
    assert e.where == "track 0, note 1" and "ends at frame 120030, past the limit of 108000 frames" in str(e)


def test_songs_built_in_code_are_checked_by_from_song():
    e = error_of(from_song, Song(120, [make_note(F(1, 100000), [0] * 6)]), kind=SongError)
    assert str(e).startswith("<input>:note 0: this note (duration 1/100000) lasts 0.0012 frames")


# ------------------------------------------------------------------------------------------------ files

def test_json_is_written_only_to_json(tmp_path):
    song = Song(100, [make_note("1/4", [0] * 6)])
    e = error_of(write_json_tab, song, tmp_path / "out.txt", kind=UserError)
    assert "out.txt: can only write the JSON tab format, to a file ending in .json (got '.txt')" in str(e)
    assert not (tmp_path / "out.txt").exists()


@pytest.mark.parametrize("suffix", [".txt", ".json", ".mid", ".gp5"])
def test_huge_tab_files_are_refused_unread(tmp_path, suffix):
    path = tmp_path / f"huge{suffix}"
    with open(path, "wb") as f:
        f.truncate(50 * 2**20)               # 50 MB, sparse: it costs no disk
    start = time.perf_counter()
    e = error_of(load_song, path, kind=SongError)
    assert time.perf_counter() - start < 2.0     # milliseconds, plus importing mido or guitarpro; it took > 240 s
    assert str(e).endswith(f"huge{suffix}: the file is larger than 1048576 bytes, the limit for a tab file (real "
                           f"tabs are tens of KB)")


def test_ascii_parser_is_linear_in_long_blank_runs():
    # Two patterns used to backtrack quadratically: 200k blanks then a letter (the string-line pattern) and a header
    # whose value holds 200k blanks (the header pattern). Each took minutes; now the whole text parses at once.
    text = " " * 200_000 + "x\ntitle: a" + " " * 200_000 + "b\n" + SYSTEM
    start = time.perf_counter()
    song = parse_ascii_tab(text)
    assert time.perf_counter() - start < 2.0
    assert song.title == "a" + " " * 200_000 + "b" and len(song.notes) == 1


def test_deeply_nested_json(tmp_path):
    deep = "[" * 200_000 + "]" * 200_000
    (tmp_path / "deep.json").write_text(deep)
    e = error_of(load_song, tmp_path / "deep.json", kind=SongError)
    assert str(e).endswith("deep.json: not a tab: JSON nested too deeply (a tab is a list of tracks, each with a "
                           "list of notes)")
    e = error_of(load_motion, tmp_path / "deep.json", kind=MotionError)
    assert str(e).endswith("deep.json: not a motion: JSON nested too deeply")
    (tmp_path / "clip.json").write_text('{"fps": 120, "frames": ' + deep + "}")
    e = error_of(read_official_json, tmp_path / "clip.json", kind=MotionError)
    assert str(e).endswith("clip.json: not a motion: JSON nested too deeply")


def test_json_tab_accepts_a_byte_order_mark(tmp_path):
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps([{"tempo": 90, "notes": [{"t": "1/4", "frets": [0] * 6}]}]).encode())
    assert load_song(path).notes[0].duration == F(1, 4)


def test_midi_messages(tmp_path):
    (tmp_path / "empty.mid").write_bytes(b"")
    e = error_of(load_song, tmp_path / "empty.mid", kind=SongError)
    assert str(e).endswith("empty.mid: cannot read as a MIDI file: the file is empty")
    mid = mido.MidiFile()
    mid.tracks.append(mido.MidiTrack([mido.Message("note_on", note=64, velocity=80, time=0),
                                      mido.Message("note_off", note=64, velocity=0, time=480)]))
    mid.save(str(tmp_path / "good.mid"))
    (tmp_path / "cut.mid").write_bytes((tmp_path / "good.mid").read_bytes()[:20])  # 14 header bytes + 6 of the track
    e = error_of(load_song, tmp_path / "cut.mid", kind=SongError)
    assert str(e).endswith("cut.mid:byte 20: cannot read as a MIDI file: it ends in the middle of the MIDI data "
                           "(truncated?)")


def test_guitar_pro_messages(tmp_path):
    (tmp_path / "empty.gp5").write_bytes(b"")
    e = error_of(load_song, tmp_path / "empty.gp5", kind=SongError)
    assert str(e).endswith("empty.gp5: cannot read as Guitar Pro 3/4/5: the file is empty")
    # a valid version string (1 length byte + 30 bytes), then nothing
    (tmp_path / "cut.gp5").write_bytes(bytes([24]) + b"FICHIER GUITAR PRO v5.00".ljust(30, b"\0"))
    e = error_of(load_song, tmp_path / "cut.gp5", kind=SongError)
    assert str(e).endswith("cut.gp5:byte 31: cannot read as Guitar Pro 3/4/5: the file ends in the middle of the "
                           "song data (truncated?)")


def test_binary_mocap_csv(tmp_path):
    path = tmp_path / "capture.csv"
    path.write_bytes(gzip.compress(b"Marker1-X,Marker1-Y,Marker1-Z\n1,2,3\n"))   # gzip starts 1f 8b: 8b is not UTF-8
    e = error_of(read_markers, path, kind=RetargetError)
    assert isinstance(e, InputError) and e.where == "line 1, column 2"
    assert "not UTF-8 text: expected a CSV of marker positions (is this a binary file?)" in str(e)


# ------------------------------------------------------------------------------------------------ --motion files

def test_bad_motion_files(tmp_path):
    lo, hi = joint_ranges("left").T
    good = save(Motion("left", 60, np.tile((lo + hi) / 2, (4, 1))), tmp_path / "good.npz")
    (tmp_path / "empty.npz").write_bytes(b"")
    (tmp_path / "empty.json").write_bytes(b"")
    (tmp_path / "cut.npz").write_bytes(good.read_bytes()[:100])
    np.savez(tmp_path / "shape.npz", qpos=np.zeros((4, 26)), hand="left", fps=60.0)
    np.savez(tmp_path / "other.npz", weights=np.zeros(3))
    np.savez(tmp_path / "fps.npz", qpos=np.zeros((2, H.N_DOF)), hand="left", fps=1e-6)
    np.save(tmp_path / "plain.npy", np.zeros((4, H.N_DOF)))
    (tmp_path / "plain.npy").rename(tmp_path / "plain.npz")
    (tmp_path / "tab.json").write_text(json.dumps([{"tempo": 90, "notes": []}]))
    (tmp_path / "binary.json").write_bytes(b'{"hand": "left", \xff}')     # 17 bytes, then one that is not UTF-8
    expected = {
        "missing.npz": "missing.npz: no such file",
        "empty.npz": "empty.npz: the file is empty",
        "empty.json": "empty.json: the file is empty",
        "cut.npz": "cut.npz: not a readable .npz file (BadZipFile: File is not a zip file); truncated?",
        "shape.npz": "shape.npz: qpos has shape (4, 26), expected (frames, 27)",
        "other.npz": "other.npz: missing array(s) qpos, hand, fps: not a motion file?",
        "fps.npz": "fps.npz: fps must lie in 1..1000, got 1e-06",
        "plain.npz": "plain.npz:byte 0: not a .npz file (a .npz is a zip archive, which starts with 'PK')",
        "tab.json": "tab.json: expected an object with 'hand', 'fps' and 'qpos'",
        "binary.json": "binary.json:byte 17: not UTF-8 text, so not a JSON motion (a .npz renamed?)",
    }
    for name, message in expected.items():
        e = error_of(load_motion, tmp_path / name, kind=MotionError)
        assert str(e).endswith(message), (name, str(e))
