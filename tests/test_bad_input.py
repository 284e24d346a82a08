"""Issue #14, input handling: every bad file a user can hand us raises an `InputError` (a `UserError` the CLI prints
as one line) naming the file and the position, and valid but unusual songs work. Every input is made here; every
expected number is worked out by hand in the comments."""
import gzip
import json
import math
import os
import re
import socket
import threading
import time
from fractions import Fraction as F
from pathlib import Path
from types import SimpleNamespace

import guitarpro
import jax
import jax.numpy as jnp
import mido
import numpy as np
import pytest
from flax import struct

from dexguitar import cli
from dexguitar.cli import build_parser, main, printable
from dexguitar.errors import InputError, UserError
from dexguitar.learn import memory as M
from dexguitar.motion import load_motion
from dexguitar.motion.format import Motion, MotionError, joint_ranges, save
from dexguitar.motion.official import read_official_json
from dexguitar.motion.retarget import RetargetError, read_markers
from dexguitar.music import load_song, load_songs
from dexguitar.errors import special_file
from dexguitar.music.song import MUTE as X, Song, SongError, make_note
from dexguitar.music.tab_ascii import parse_ascii_tab
from dexguitar.music.tab_json import write_json_tab
from dexguitar.music.timeline import from_song
from dexguitar.perform.evaluate import UNDEFINED, dumps, summarize
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


# ------------------------------------------------------------------------------------------------ special files

def finishes(fn, *args, seconds=20.0):
    """What fn(*args) returns or raises, run in a thread that must end within `seconds` (a FIFO's open blocks)."""
    out = {}

    def run():
        try:
            out["value"] = fn(*args)
        except BaseException as e:          # noqa: BLE001 - handed to the test
            out["value"] = e
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"{fn.__name__} still runs after {seconds} s"
    return out.get("value")


def test_special_files_are_refused_before_any_open(tmp_path, capsys):
    fifo = tmp_path / "song.json"
    os.mkfifo(fifo)
    folder = tmp_path / "folder.txt"
    folder.mkdir()
    sock_path = tmp_path / "s.mid"
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(sock_path))
    try:
        kinds = {fifo: "a FIFO (named pipe)", folder: "a directory", sock_path: "a socket",
                 Path("/dev/null"): "a character device"}
        for path, kind in kinds.items():
            assert special_file(path) == kind
            e = finishes(load_song, path)
            assert isinstance(e, SongError) and str(e) == f"{path}: is {kind}, not a tab file"
        assert special_file(tmp_path / "missing.json") is None
        assert special_file(json_tab(tmp_path / "plain.json", 90, ["1/4"])) is None
        # eval and train take lists of songs (folders too): a FIFO there is named as such, not "no such file"
        e = finishes(load_songs, [fifo])
        assert str(e) == f"{fifo}: is a FIFO (named pipe), not a tab file"
        # the command: song info and convert say it in one line, exit 2
        assert finishes(main, ["song", "info", str(fifo)]) == 2
        assert finishes(main, ["song", "convert", str(fifo), str(tmp_path / "out.json")]) == 2
        err = capsys.readouterr().err.splitlines()
        assert err == [f"error: {fifo}: is a FIFO (named pipe), not a tab file"] * 2
        # every other file a user names is read through `errors.read_input`: a reference motion, for one
        motion_fifo = tmp_path / "clip.npz"
        os.mkfifo(motion_fifo)
        e = finishes(load_motion, motion_fifo)
        assert isinstance(e, MotionError) and str(e) == f"{motion_fifo}: is a FIFO (named pipe), not a motion file"
    finally:
        sock.close()


# ------------------------------------------------------------------------------------------------ nothing to play

def test_a_song_of_rests_is_refused_in_every_format(tmp_path):
    muted = json_tab(tmp_path / "muted.json", 90, ["1/4", "1/2"])
    data = json.loads(muted.read_text())
    for note in data[0]["notes"]:
        note["frets"] = [X] * 6
    muted.write_text(json.dumps(data))
    assert str(error_of(load_song, muted, kind=SongError)) == \
        f"{muted}: nothing to play: all 2 notes are rests (every string muted)"
    gp_song = guitarpro.Song(title="Rest", tempo=96)             # one standard-tuned guitar track, one measure
    voice = gp_song.tracks[0].measures[0].voices[0]
    voice.beats.append(guitarpro.Beat(voice, duration=guitarpro.Duration(value=1), status=guitarpro.BeatStatus.rest))
    guitarpro.write(gp_song, str(tmp_path / "rest.gp5"))
    assert str(error_of(load_song, tmp_path / "rest.gp5", kind=SongError)) == \
        f"{tmp_path / 'rest.gp5'}: nothing to play: its one note is a rest (every string muted)"
    (tmp_path / "rest.txt").write_text(SYSTEM.replace("0---", "x---"))   # an ASCII tab of a muted strum
    assert "the tab has no notes" in str(error_of(load_song, tmp_path / "rest.txt", kind=SongError))


# ------------------------------------------------------------------------------------------------ NaN never in JSON

def strict_json(text):
    def refuse(name):
        raise AssertionError(f"{name} in JSON output")
    return json.loads(text, parse_constant=refuse)


def test_undefined_scores_are_null_with_a_reason_in_json(monkeypatch, capsys):
    # one open-string note played cleanly: the right hand picked 1 of 1 (F1 1), the left hand had nothing to press
    # and pressed nothing, so no note concerned it and its F1 is undefined
    zero = {"precision": 0.0, "recall": 0.0, "f1": 0.0, "tp": 0, "predicted": 0, "targets": 0}
    row = {"note": 0, "frame": 30, "frets": [0, X, X, X, X, X], "chord": False, "rest": False, "left": zero,
           "right": {"precision": 1.0, "recall": 1.0, "f1": 1.0, "tp": 1, "predicted": 1, "targets": 1}}
    summary = summarize([row], ("left", "right"))
    assert math.isnan(summary["left"]["f1"]) and summary["left"]["notes"] == 0 and summary["right"]["f1"] == 1.0
    assert summary["left"]["undefined"] == UNDEFINED
    assert strict_json(dumps(summary))["left"] == {"precision": None, "recall": None, "f1": None, "notes": 0,
                                                   "undefined": UNDEFINED}
    assert strict_json(dumps([np.float32("inf"), np.int64(3), (1.5,)])) == [None, 3, [1.5]]
    # `dexguitar eval --json` prints it so (the policy and the play itself stand in)
    monkeypatch.setattr(cli.PO, "load", lambda path: ({}, {"hand": "right"}))
    monkeypatch.setattr(cli.PO.PolicySpec, "from_meta", staticmethod(lambda meta: SimpleNamespace(kind="policy")))
    monkeypatch.setattr(cli, "evaluate", lambda params, spec, songs, env_config=None, record=False: {
        "Ode": {"summary": summary, "notes": [row]}})
    assert main(["eval", "--ckpt", "C", "--song", "ode_to_joy", "--json"]) == 0
    assert strict_json(capsys.readouterr().out)["Ode"]["left"]["f1"] is None
    assert main(["eval", "--ckpt", "C", "--song", "ode_to_joy"]) == 0
    assert "left F1 undefined (0 notes: nothing to press or pick)  right F1 1.000" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------------ tracks

def three_tracks(path, bad=None):
    tracks = [{"tempo": tempo, "title": name, "notes": [{"t": "1/4", "frets": [fret, X, X, X, X, X]}]}
              for tempo, name, fret in ((90, "lead", 5), (100, "rhythm", 3), (110, "bass", 0))]
    if bad is not None:
        tracks[bad]["notes"][0]["frets"] = [0] * 5             # five strings
    path.write_text(json.dumps(tracks))
    return path


def test_tracks_of_a_multi_track_tab(tmp_path, capsys):
    bad = three_tracks(tmp_path / "bad.json", bad=1)
    e = error_of(load_song, bad, kind=SongError)
    assert e.where == "track 1, note 0" and "'frets' must be 6 integers" in str(e)
    assert load_song(bad, track=2).notes[0].frets == (0, X, X, X, X, X)          # the user's choice stands
    differ = three_tracks(tmp_path / "differ.json")
    assert str(error_of(load_song, differ, kind=SongError)) == (
        f"{differ}: 3 different tracks (0: 'lead', 90 BPM, 1 note; 1: 'rhythm', 100 BPM, 1 note; 2: 'bass', "
        f"110 BPM, 1 note): choose one with --track N (0..2)")
    same = tmp_path / "same.json"
    same.write_text(json.dumps([json.loads(differ.read_text())[0]] * 2))
    assert load_song(same).tempo == 90                                           # copies of one song: read
    assert main(["song", "info", str(differ), "--track", "1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["tempo"] == 100
    (tmp_path / "one.txt").write_text(SYSTEM)
    assert load_song(tmp_path / "one.txt", track=0).n_notes == 1
    assert str(error_of(lambda p: load_song(p, track=1), tmp_path / "one.txt", kind=SongError)) == \
        f"{tmp_path / 'one.txt'}: track 1 does not exist: a .txt file holds one track (0)"
    assert load_song("ode_to_joy", track=0) == load_song("ode_to_joy")
    with pytest.raises(SystemExit):
        build_parser().parse_args(["song", "info", str(differ), "--track", "-1"])
    assert "tracks are numbered from 0, got -1" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------------ ASCII tab lines

@pytest.mark.parametrize("extra, message", [
    ("|--3-|", "line 7, column 1: one string line too many (or one missing): lines 1-7 are 7 consecutive string "
               "lines, and a system has 6"),
    ("3---|", "line 7, column 1: this line looks like a string line of tab but its body starts with neither '|' "
              "nor '-'"),
    ("  x--3-", "line 7, column 3: this line looks like a string line of tab but its body starts with neither"),
    ("h|-3--|", "line 7, column 1: this line looks like a string line of tab but 'h' is not a string name"),
    ("|-3 --|", "line 7, column 1: this line looks like a string line of tab but its body has a blank in it"),
])
def test_an_extra_tab_line_is_refused_with_its_number(tmp_path, extra, message):
    path = tmp_path / "seven.txt"
    path.write_text(SYSTEM + extra + "\n")
    assert f"seven.txt:{message}" in str(error_of(load_song, path, kind=SongError))


def test_text_lines_beside_a_system_are_still_text():
    # a dashed separator, a repeat count, a chord chart, lyrics with a hyphen, a time: none is a string line
    text = "-------\n" + SYSTEM + "x2\n| C | G |\nA-men\n3:45 -- fine\n1-2-3-4\n"
    assert parse_ascii_tab(text).n_notes == 1


# ------------------------------------------------------------------------------------------------ --size, --envs

@pytest.mark.parametrize("size, message", [
    ("0x0", "0x0 is outside 16..7680 x 16..4320"), ("99999x99999", "99999x99999 is outside 16..7680 x 16..4320"),
    ("641x360", "641x360: width and height must be even"), ("wide", "expected WIDTHxHEIGHT, e.g. 1280x720"),
])
def test_video_sizes_out_of_range_are_refused(size, message, capsys):
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args(["play", "--song", "s", "--size", size])
    assert info.value.code == 2 and f"argument --size: {message}" in capsys.readouterr().err
    args = build_parser().parse_args(["play", "--song", "s", "--size", "7680x4320"])
    assert args.size == (7680, 4320)
    assert build_parser().parse_args(["play", "--song", "s"]).size == (1280, 720)


@struct.dataclass
class _Body:
    link_hist: jax.ShapeDtypeStruct


@struct.dataclass
class _EnvState:
    obs: jax.ShapeDtypeStruct
    privileged: jax.ShapeDtypeStruct
    body: _Body
    rest: jax.ShapeDtypeStruct


@struct.dataclass
class _TrainState:
    env: _EnvState
    params: jax.ShapeDtypeStruct


def test_env_counts_that_cannot_fit_are_refused():
    f32 = lambda *shape: jax.ShapeDtypeStruct(shape, np.float32)          # noqa: E731
    # 4 envs, each state 1000 float32 = 4000 B, of which obs 100 + privileged 10 + link history 50 floats = 640 B;
    # a horizon of 8: per env 2 x 4000 + 8 x 640 = 13120 B; besides the envs 1000 float32 of parameters = 4000 B
    shapes = _TrainState(_EnvState(f32(4, 100), f32(4, 10), _Body(f32(4, 50)), f32(4, 840)), f32(1000))
    trainer = SimpleNamespace(config=SimpleNamespace(num_envs=4, horizon=8), state_shapes=shapes)
    assert M.tree_bytes(shapes.env) == 4 * 4000
    assert M.training_bytes(trainer) == (13120, 4000)
    env = SimpleNamespace(reset=lambda key: {"qpos": jnp.zeros((27,), jnp.float32), "t": jnp.int32(0)})
    assert M.env_bytes(env) == 27 * 4 + 4
    gib = 2**30
    M.check_envs(4, 13120, 4000, free=(gib, "here"))                                  # 56 KB: fine
    M.check_envs(16_384, 130 * 1024, 70 * 2**20, free=(60 * gib, "1 H100"))           # 2.1 GB of 60 GB: fine
    with pytest.raises(UserError) as info:
        M.check_envs(100_000_000, 13120, 4000, free=(4 * gib, "this machine"))
    # 1e8 x 13120 B + 4000 B = 1.312e12 B = 1221.9 GiB; (4 GiB - 4000 B) // 13120 B = 327,360 envs
    assert str(info.value) == ("--envs 100,000,000: needs at least 1,221.9 GiB (13 KiB per env and 0.0 MiB "
                               "besides), but this machine has 4.0 GiB free; at most about 327,360 envs fit")
    have, where = M.free_memory()                   # this machine (tests run on a CPU): a positive number of bytes
    assert have > 0 and where == "this machine"


def test_train_and_bench_refuse_env_counts_before_allocating(tmp_path, monkeypatch, capsys):
    # stand-ins whose env state is 1e6 B; bench holds two per env (a step's input and output), so 1e8 envs need
    # 2e14 B = 186,264.5 GiB, past any machine
    f32 = lambda *shape: jax.ShapeDtypeStruct(shape, np.float32)          # noqa: E731
    monkeypatch.setattr(cli, "default_songs", lambda hand: None)
    monkeypatch.setattr(cli.E, "make", lambda hand, songs, **config: SimpleNamespace(
        reset=lambda key: jnp.zeros((250_000,), jnp.float32)))
    monkeypatch.setattr(cli, "bench_env", lambda *a, **k: pytest.fail("bench ran"))
    assert main(["bench", "env", "--envs", "4", "100000000"]) == 2
    assert re.fullmatch(r"error: --envs 100,000,000: needs at least 186,264\.5 GiB \(1,953 KiB per env\), but this "
                        r"machine has [\d,.]+ [MG]iB free; at most about [\d,]+ envs fit\n", capsys.readouterr().err)
    n = 100_000_000

    class Trainer:
        def __init__(self, config, *args):
            self.config = config
            self.state_shapes = _TrainState(_EnvState(f32(n, 250_000), f32(n, 1), _Body(f32(n, 1)), f32(n, 1)),
                                            f32(1))
    monkeypatch.setattr(cli, "Trainer", Trainer)
    monkeypatch.setattr(cli, "reference_frames", lambda motion: None)
    monkeypatch.setattr(cli, "train", lambda *a, **k: pytest.fail("training started"))
    assert main(["train", "--hand", "left", "--envs", str(n), "--song", "ode_to_joy", "--out",
                 str(tmp_path / "run")]) == 2
    assert "error: --envs 100,000,000: needs at least" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------------ raw bytes

def test_error_messages_escape_unprintable_characters(tmp_path, capsys):
    path = tmp_path / "nul.txt"
    path.write_bytes(b"title: a\x00b\ntempo: 9\x0700\n" + SYSTEM.encode())
    assert main(["song", "info", str(path)]) == 2
    err = capsys.readouterr().err
    assert err == f"error: {path}:line 2, column 8: malformed tempo '9\\x0700': expected a positive number of " \
                  "quarter-note beats per minute, e.g. 'tempo: 100'\n"
    assert printable("a\x00b\nc\u200bé") == "a\\x00b\\nc\\u200bé"
