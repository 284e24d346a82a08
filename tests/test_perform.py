"""Performance output: string synthesis pitch, the audio mix, string colours, WAV files, per-note verdicts, the duet
observation split, the caption's running F1, rendering (`offscreen_gl`: skipped without an offscreen GL, failed under
CI) and the no-GL fallback. No env rollout: everything runs on hand-made data. The stage itself: test_stage.py."""
import numpy as np
import pytest

from dexguitar.perform import audio as A
from dexguitar.perform import colors as C
from dexguitar.world.guitar import GUITAR

FS = 44100


def fundamental(x, fs=FS):
    """Fundamental of a harmonic sound: the lowest spectral peak within 20 dB of the strongest (a low string's
    harmonics can beat its fundamental), refined by parabolic interpolation on the log magnitude."""
    x = (x - x.mean()) * np.hanning(len(x))
    n = 1 << 20
    mag = np.abs(np.fft.rfft(x, n))
    lo = int(40 * n / fs)
    strong = mag >= 0.1 * mag[lo:].max()
    peaks = [k for k in range(lo, len(mag) - 1) if strong[k] and mag[k] >= mag[k - 1] and mag[k] >= mag[k + 1]]
    k = peaks[0]
    a, b, c = np.log(mag[k - 1:k + 2])
    return (k + 0.5 * (a - c) / (a - 2 * b + c)) * fs / n


@pytest.mark.parametrize("string,fret", [(5, 0), (1, 12), (6, 0), (3, 7), (1, 22)])
def test_pluck_pitch_within_one_percent(string, fret):
    f = GUITAR.frequency(string, fret)
    x = A.pluck(f, 1.0, FS)
    assert x.shape == (FS,) and x.dtype == np.float32
    assert np.max(np.abs(x)) == pytest.approx(1.0, abs=1e-3)
    assert fundamental(x) == pytest.approx(f, rel=0.01)
    assert np.abs(x[-2000:]).max() < np.abs(x[:2000]).max()          # it decays


def test_pluck_reference_pitches():
    assert A.string_frequency(5, 0) == pytest.approx(110.0)
    assert A.string_frequency(1, 12) == pytest.approx(659.255, abs=0.01)
    assert fundamental(A.pluck(659.255, 1.0)) == pytest.approx(659.255, rel=0.002)


def test_render_audio_onsets_and_silence():
    first = A.render_audio([(0.25, 1, 0)], 1.0, FS)
    both = A.render_audio([(0.25, 1, 0), (0.5, 5, 3)], 1.0, FS)
    assert both.shape == (FS,)
    on1, on2 = int(0.25 * FS), int(0.5 * FS)
    assert np.all(both[:on1] == 0)                                       # silence before the first pick
    assert np.abs(both[on1:on1 + 50]).max() > 0.05                        # sound right at it
    assert np.array_equal(both[:on2], first[:on2])                       # the second note starts at 0.5 s ...
    assert np.abs(both[on2:on2 + 50] - first[on2:on2 + 50]).max() > 0.05  # ... and not later
    assert np.abs(both).max() < 1.0


def test_render_audio_repick_and_mute_cut_the_string():
    x = A.render_audio([(0.0, 2, 1), (0.5, 2, -1)], 1.0, FS)             # fret -1 silences the string
    assert np.abs(x[: FS // 4]).max() > 0.05
    assert np.all(x[FS // 2:] == 0)


def test_events_from_info():
    press = np.zeros((20, 6), int)
    picks = np.zeros((20, 6), bool)
    press[:, 1] = 3
    picks[2, 1] = True                  # string 2 picked at fret 3
    picks[5, 0] = True                  # string 1 open
    press[10:, 1] = 5                   # slide to fret 5 while ringing: a softer restart
    press[12, 0] = 2                    # a one-frame flicker on string 1: ignored
    ev = A.events_from_info({"press": press, "picks": picks}, fps=60)
    assert [(round(e.time * 60), e.string, e.fret, e.amplitude) for e in ev] == [
        (3, 2, 3, 1.0), (6, 1, 0, 1.0), (11, 2, 5, 0.4)]
    assert A.events_from_info({"press": press, "picks": picks}, legato=False)[-1].fret == 0


def test_wav_round_trip(tmp_path):
    x = np.sin(2 * np.pi * 440 * np.arange(4410) / FS).astype(np.float32) * 0.5
    path = A.write_wav(tmp_path / "a.wav", x, FS)
    import wave
    with wave.open(str(path)) as w:
        assert (w.getnchannels(), w.getsampwidth(), w.getframerate(), w.getnframes()) == (1, 2, FS, 4410)
    y, rate = A.read_wav(path)
    assert rate == FS and np.abs(y - x).max() < 1.0 / 32767 + 1e-6
    A.write_wav(tmp_path / "clip.wav", np.array([2.0, -2.0]), FS)          # clipped, not wrapped
    assert np.allclose(A.read_wav(tmp_path / "clip.wav")[0], [1.0, -1.0])


# ------------------------------------------------------------------------------------------------ colours

def test_string_colors_rule():
    goal = np.array([-1, 3, 0, 0, 0, 0])        # string 1 open, string 2 at fret 3
    targets = np.array([1, 1, 0, 0, 0, 0], bool)
    press = np.array([0, 3, 0, 0, 0, 0])
    no = np.zeros(6, bool)
    names = C.color_names(C.string_colors(goal, targets, press, no, no))
    assert names == ["yellow", "yellow", "grey", "grey", "grey", "grey"]
    names = C.color_names(C.string_colors(goal, targets, np.array([2, 2, 0, 0, 0, 0]), no, no))
    assert names[:2] == ["grey", "grey"]        # pressed where it should ring open / at the wrong fret


def test_rollout_colors_sequence():
    # note 0: string 2 at fret 3 (target); note 1: string 1 open (target)
    goal_rows = np.array([[0, 3, 0, 0, 0, 0], [-1, 0, 0, 0, 0, 0]])
    pick_rows = np.array([[0, 1, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0]], bool)
    T = 8
    press, picks = np.zeros((T, 6), int), np.zeros((T, 6), bool)
    note = np.array([0, 0, 0, 0, 1, 1, 1, 1])
    press[1:4, 1] = 3                   # pressed right from step 1
    picks[2, 1] = True                  # picked while pressed: green
    picks[3, 3] = True                  # a string that is no target: red
    press[5, 0] = 2                     # note 1: string 1 pressed though it should ring open ...
    picks[5, 0] = True                  # ... and picked: red
    picks[6, 0] = True                  # picked again: still red
    names = [C.color_names(c) for c in C.rollout_colors(press, picks, note, goal_rows, pick_rows)]
    assert names[0][1] == "grey"                         # target, not pressed yet
    assert names[1][1] == "yellow"                       # pressed right, waiting for the pick
    assert names[2][1] == "green" and names[3][1] == "green"
    assert names[3][3] == "red"
    assert names[4][:4] == ["yellow", "grey", "grey", "grey"]   # new note: reset (open string 1 ready)
    assert names[5][0] == "red" and names[6][0] == "red" and names[7][0] == "red"


def test_second_pick_turns_green_red():
    goal, targets, press = np.array([-1, 0, 0, 0, 0, 0]), np.array([1, 0, 0, 0, 0, 0], bool), np.zeros(6, int)
    picked, ok = C.update_so_far(np.zeros(6, bool), np.zeros(6, bool), targets, goal, targets, press)
    assert C.color_names(C.string_colors(goal, targets, press, picked, ok))[0] == "green"
    picked, ok = C.update_so_far(picked, ok, targets, goal, targets, press)
    assert C.color_names(C.string_colors(goal, targets, press, picked, ok))[0] == "red"


# ------------------------------------------------------------------------------------------------ play

def test_an_unsynchronized_pair_acts_as_each_hand_alone(tmp_path):
    """`play.pair`: two single-hand exports played as a synchronizer with a zero output layer give each hand's own
    action on its own slice of the duet observation (frame t = [left 208 | right 208], then the two goals)."""
    import jax
    import jax.numpy as jnp

    from dexguitar.learn import networks as N
    from dexguitar.learn import policy as PO
    from dexguitar.perform.play import pair
    hands = {}
    for i, hand in enumerate(("left", "right")):
        params = {"policy": N.init_params(N.Policy(27), jax.random.PRNGKey(i), (2, 208), (35,)),
                  "obs_norm": N.normalizer_init(208)}
        params["policy"] = jax.tree.map(lambda x: x + 0.05, params["policy"])       # the latent matters
        PO.export(tmp_path / hand, params, {"hand": hand, "action_size": 27, "goal_size": 35, "obs_size": 451})
        hands[hand] = PO.load(tmp_path / hand)[0]
    params, spec = pair(tmp_path / "left", tmp_path / "right")
    obs = jax.random.normal(jax.random.PRNGKey(5), (3, 902))
    both = PO.make_act(params, spec)(obs)
    frames = obs[:, :832].reshape(3, 2, 2, 208)
    for i, (hand, goal) in enumerate((("left", obs[:, 832:867]), ("right", obs[:, 867:]))):
        p = hands[hand]
        alone, _ = N.Policy(27).apply(p["policy"], N.normalize(p["obs_norm"], frames[:, :, i]), goal)
        np.testing.assert_allclose(both[:, 27 * i:27 * (i + 1)], alone, atol=1e-6)
    assert float(jnp.abs(both).max()) > 1e-3


def hand_made_performance():
    """A 4-note song and a recording of it: right, late, picked before the press, rest."""
    from dexguitar.music.song import Song, make_note
    X = -1
    song = Song(120, [make_note("1/4", [0, X, X, X, X, X]), make_note("1/4", [X, 3, X, X, X, X]),
                      make_note("1/4", [X, 1, X, X, X, X]), make_note("1/4", [X, X, X, X, X, X])])
    # window rows: the env's 5-frame grace rest (song note -1), then the song's 4 notes of 30 frames
    dur = np.array([5, 30, 30, 30, 30])
    onset = np.concatenate([[0], np.cumsum(dur)])
    T = int(onset[-1])
    row = np.repeat(np.arange(5), dur)
    rec = {"press": np.zeros((T, 6), int), "picks": np.zeros((T, 6), bool), "song_note": row - 1, "row": row,
           "note_end": np.zeros(T, bool),
           "goal_left": np.array([[0] * 6, [-1, 0, 0, 0, 0, 0], [0, 3, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0] * 6]),
           "pick": np.array([[0] * 6, [1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0] * 6], bool),
           "dur": dur, "onset": onset}
    for h in ("left", "right", "both"):
        rec[h] = np.zeros((T, 6), np.float32)
    rec["note_end"][onset[1:] - 1] = True
    perfect, zero, rest = [1, 1, 1, 1, 1, 1], [0, 0, 0, 0, 1, 1], [1, 1, 1, 0, 0, 0]
    for t in (4, 124):                                               # the grace rest and the song's rest
        rec["both"][t] = rec["right"][t] = rec["left"][t] = rest
    rec["picks"][5 + 2, 0] = True                                    # note 0: right
    rec["both"][34], rec["right"][34], rec["left"][34] = perfect, perfect, rest
    rec["press"][40:65, 1] = 3                                       # note 1: pressed early, picked at frame 15
    rec["picks"][50, 1] = True
    rec["both"][64], rec["right"][64], rec["left"][64] = zero, perfect, perfect
    rec["press"][70:95, 1] = 1                                       # note 2: picked at frame 2, pressed at 5
    rec["picks"][67, 1] = True
    rec["both"][94], rec["right"][94], rec["left"][94] = zero, zero, perfect
    # as the env reports them: each note judged within itself at its end ("both_now"), and its final verdict at the
    # next note's end ("both"; note 1's hold does not run on: string 2 is released at frame 65)
    ends = onset[1:] - 1
    rec["both_now"], rec["both"] = rec["both"], np.zeros_like(rec["both"])
    rec["both"][ends[1:]] = rec["both_now"][ends[:-1]]
    return song, rec


def test_note_verdicts():
    from dexguitar.perform.play import note_verdicts, render_colors
    song, rec = hand_made_performance()
    rows = note_verdicts(rec, song)
    assert [r["note"] for r in rows] == [0, 1, 2, 3]          # a clean grace rest is not reported
    assert [r["verdict"] for r in rows] == ["right", "late", "wrong", "rest"]
    assert rows[2]["why"] == "picked before the press" and rows[2]["picked"] == [2]
    assert rows[1]["first_pick"] == 15 and rows[1]["onset_frame"] == 35
    names = [C.color_names(c) for c in render_colors(rec)]
    assert names[7][0] == "green" and names[49][1] == "yellow" and names[50][1] == "green"
    assert names[67][1] == "red" and names[66][1] == "grey"


def test_running_f1_and_caption():
    import dataclasses

    from dexguitar.perform.play import caption, note_verdicts, running_f1
    song, rec = hand_made_performance()
    rows = note_verdicts(rec, song)
    notes, f1 = running_f1(rows, len(rec["press"]))
    # both-hands F1 of the notes that end at frames 34, 64, 94 (right, late, wrong: 1, 0, 0); the rest at 124 has
    # no target and no pick, so it does not count
    assert notes[33] == 0 and np.isnan(f1[33])
    assert (notes[34], f1[34]) == (1, 1.0) and (notes[63], f1[63]) == (1, 1.0)
    assert (notes[64], f1[64]) == (2, 0.5)
    assert notes[94] == 3 and f1[94] == pytest.approx(1 / 3)
    assert notes[-1] == 3 and f1[-1] == pytest.approx(1 / 3)
    text = caption(dataclasses.replace(song, title="Four notes"), notes[64], f1[64]).splitlines()
    assert text == ["Four notes", "120 bpm", "F1 both hands: 0.500 (2 notes)", "yellow: pressed, ready to pick",
                    "green: picked right", "red: picked wrong"]
    assert caption(song, 1, 1.0).splitlines()[2] == "F1 both hands: 1.000 (1 note)"
    assert caption(song, 0, float("nan")).splitlines()[2] == "F1 both hands: -"


def test_the_legend_names_the_colours_the_strings_take():
    """Each colour the legend names is one the strings take, in the situation it names (`string_colors`): string 1
    pressed at its goal fret 2 and not picked yet, picked once then, and string 2 picked though no target."""
    goal = press = np.array([2, 0, 0, 0, 0, 0])
    targets, no = np.array([1, 0, 0, 0, 0, 0], bool), np.zeros(6, bool)
    picked, ok = C.update_so_far(no, no, np.array([1, 1, 0, 0, 0, 0], bool), goal, targets, press)
    ready = C.color_names(C.string_colors(goal, targets, press, no, no))[0]
    right, wrong = C.color_names(C.string_colors(goal, targets, press, picked, ok))[:2]
    assert C.legend().splitlines() == [f"{ready}: pressed, ready to pick", f"{right}: picked right",
                                       f"{wrong}: picked wrong"]


def perform_hand_made(tmp_path, monkeypatch, **kw):
    """perform on the hand-made recording (its `play` replaced: no rollout)."""
    from dexguitar.perform import play as P
    from dexguitar.world import scene as S
    song, rec = hand_made_performance()
    T = len(rec["press"])
    rec.update(qpos=np.tile(S.build_model("duet").key_qpos[0], (T, 1)), frames=T, rollout_seconds=0.0)
    monkeypatch.setattr(P, "play", lambda *a, **k: rec)
    return P.perform(song, None, None, out_prefix=tmp_path / "perf", **kw), T


def test_perform_writes_outputs_without_ffmpeg(tmp_path, monkeypatch, offscreen_gl):
    """perform end to end on the hand-made recording (no rollout): PNG sheet, WAV and JSON report."""
    import json

    from dexguitar.perform import play as P
    report, T = perform_hand_made(tmp_path, monkeypatch, video=False, quiet=True)
    assert report["counts"] == {"right": 1, "late": 1, "wrong": 1, "rest": 1}
    assert report["summary"]["both"]["f1"] == pytest.approx(1 / 3)
    saved = json.loads((tmp_path / "perf-report.json").read_text())
    assert saved["counts"] == report["counts"] and saved["files"]["frames"].endswith("perf.png")
    x, rate = A.read_wav(tmp_path / "perf.wav")
    assert len(x) == round(T / 60 * rate) and np.all(x[: int(7 / 60 * rate)] == 0) and np.abs(x).max() > 0.05
    assert "late" in P.format_report(report)


def test_perform_without_gl_writes_audio_and_report(tmp_path, monkeypatch, capsys):
    """No offscreen OpenGL (the context creation fails): the WAV, the report and the per-note table are written
    all the same, and one line says what to install."""
    import json

    from dexguitar.motion import glcheck

    def no_gl(width, height):
        raise glcheck.NoGL("no offscreen OpenGL (test)")
    monkeypatch.setattr(glcheck, "gl_context", no_gl)
    report, T = perform_hand_made(tmp_path, monkeypatch, video=False)     # (no ffmpeg needed for the PNG path)
    out, err = capsys.readouterr()
    assert err.strip().splitlines() == [
        "no offscreen OpenGL: apt-get install libosmesa6 (or an EGL driver), then run again for the video"]
    assert "late" in out and "verdicts: right 1, late 1, wrong 1, rest 1" in out
    assert set(report["files"]) == {"audio", "report"}
    assert not (tmp_path / "perf.mp4").exists() and not (tmp_path / "perf.png").exists()
    assert json.loads((tmp_path / "perf-report.json").read_text())["counts"]["late"] == 1
    assert len(A.read_wav(tmp_path / "perf.wav")[0]) == round(T / 60 * FS)


def test_video_captions_end_on_the_report(tmp_path, monkeypatch):
    """30 fps from the 60 Hz recording: a video frame's caption counts the notes judged by the end of the time it
    shows, so an odd-length recording still ends on the report's F1."""
    from pathlib import Path

    from dexguitar.perform import video as V
    seen = {}
    monkeypatch.setattr(V, "have_ffmpeg", lambda: True)
    monkeypatch.setattr(V, "render_video", lambda model, q, c, out, **k: seen.update(k, q=q) or Path(out))
    report, T = perform_hand_made(tmp_path, monkeypatch, captions=True, quiet=True)
    both = report["summary"]["both"]
    assert T % 2 == 1 and len(seen["captions"]) == len(seen["q"]) == (T + 1) // 2
    assert seen["captions"][0].splitlines()[2] == "F1 both hands: -"
    assert seen["captions"][-1].splitlines()[2] == f"F1 both hands: {both['f1']:.3f} ({both['notes']} notes)"
    assert both["notes"] == 3


def test_the_report_json_and_table_give_frets_string_6_first(tmp_path, monkeypatch):
    """Note 1 of the hand-made song is string 2 at fret 3 (a Song's frets, string 1 first: [x, 3, x, x, x, x]): the
    written report and its table both give it string 6 first."""
    import json
    from pathlib import Path

    from dexguitar.perform import play as P
    from dexguitar.perform import video as V
    monkeypatch.setattr(V, "have_ffmpeg", lambda: True)
    monkeypatch.setattr(V, "render_video", lambda model, q, c, out, **k: Path(out))
    perform_hand_made(tmp_path, monkeypatch, quiet=True)
    saved = json.loads((tmp_path / "perf-report.json").read_text())
    note = next(r for r in saved["notes"] if r["note"] == 1)
    assert note["frets_6_to_1"] == [-1, -1, -1, -1, 3, -1] and "frets" not in note
    row = next(line for line in P.format_report(saved).splitlines() if line.split()[0] == "1")
    assert row.split()[2:8] == ["x", "x", "x", "x", "3", "x"]


def test_the_demo_songs_report_counts_its_notes_as_its_f1_does():
    """The demo's song, counted by hand from its tab (`music/songs/strum_g_c_d.txt`): bars 1-3, 5 and 6 strum
    D-DU-UDU (6 chords each), bars 4 and 7 two chords and two muted chucks (x-only columns, rests: notes 19, 21,
    35, 37), bar 8 one held G. 39 notes: 35 chords and 4 rests. Played right (every chord pressed and picked), the
    header and each hand's F1 count the same 35 notes; the rests are counted apart."""
    from dexguitar.music import load_song
    from dexguitar.perform.evaluate import summarize
    from dexguitar.perform.play import format_report, report_note
    song = load_song("strum_g_c_d")
    rows = []
    for i, note in enumerate(song.notes):
        pressed, picked = sum(f > 0 for f in note.frets), sum(f >= 0 for f in note.frets)
        row = {"note": i, "frame": 10 * i, "frets": list(note.frets), "chord": note.is_chord, "rest": note.is_rest,
               "onset_frame": 10 * i, "verdict": "rest" if note.is_rest else "right", "why": "", "picked": []}
        for h, n in (("left", pressed), ("right", picked), ("both", picked)):
            row[h] = {"precision": 1.0, "recall": 1.0, "f1": 1.0, "tp": n, "predicted": n, "targets": n}
        rows.append(row)
    summary = summarize(rows, ("left", "right", "both"))
    assert [summary[h]["notes"] for h in ("left", "right", "both")] == [35, 35, 35]
    report = {"title": song.title, "seconds": song.seconds, "notes": [report_note(r) for r in rows],
              "counts": {"right": 35, "late": 0, "wrong": 0, "rest": 4}, "summary": summary}
    lines = format_report(report).splitlines()
    assert lines[0] == "Strumming G - C - D: 19.2 s, 35 notes and 4 rests judged"
    assert sum(line.endswith("(P 1.000 R 1.000, 35 notes)") for line in lines) == 3
    table = {int(line.split()[0]): line.split()[2:8] for line in lines[2:41]}
    assert sorted(table) == list(range(39)) and lines[41].startswith("verdicts:")
    assert [i for i, frets in table.items() if frets == ["x"] * 6] == [19, 21, 35, 37]
    assert table[0] == ["3", "2", "0", "0", "0", "3"] and table[12] == ["x", "3", "2", "0", "1", "0"]   # G, C
    assert table[24] == ["x", "x", "0", "2", "3", "2"] and "3 2 0 0 0 3" in summary["chords"]           # D


def test_play_options(monkeypatch):
    """`dexguitar play` passes the video options on: 1280 x 720 at 30 fps from the front by default."""
    from dexguitar import cli
    seen = {}
    monkeypatch.setattr(cli.PL, "perform", lambda *a, **k: seen.update(k) or {})
    monkeypatch.setattr(cli.PL, "pair", lambda left, right: ({}, None))
    assert cli.main(["play", "--left", "L", "--right", "R", "--song", "s"]) == 0
    assert (seen["width"], seen["height"], seen["video_fps"], seen["camera"], seen["captions"]) == (
        1280, 720, 30.0, "front", False)
    assert cli.main(["play", "--left", "L", "--right", "R", "--song", "s", "--camera", "closeup", "--caption",
                     "--size", "640x360"]) == 0
    assert (seen["width"], seen["height"], seen["camera"], seen["captions"]) == (640, 360, "closeup", True)
    assert cli.main(["play", "--left", "L", "--song", "s"]) == 2                  # a pair needs both hands


# ------------------------------------------------------------------------------------------------ rendering

@pytest.fixture(scope="module")
def duet_model():
    from dexguitar.world import stage
    return stage.stage_model("duet")


def test_render_frames_png_colours_strings(tmp_path, duet_model, offscreen_gl):
    from dexguitar.motion.render import png_size
    from dexguitar.perform.video import SceneRenderer, render_frames_png
    q = np.tile(duet_model.key_qpos[0], (2, 1))
    grey = np.tile(C.GREY, (6, 1))
    with SceneRenderer(duet_model, 160, 90) as r:
        plain, red = r.frame(q[0], grey), r.frame(q[0], np.tile(C.RED, (6, 1)))
    assert plain.std() > 5                                            # the scene, not a blank (camera) image
    diff = np.abs(red.astype(int) - plain.astype(int)).sum(-1) > 30
    assert diff.any()                                                  # the strings take the colour
    redness = red[diff][:, 0].astype(int) - red[diff][:, 1:].max(-1)
    assert np.mean(redness > 0) > 0.8
    out = render_frames_png(duet_model, q, np.stack([grey, grey]), tmp_path / "s.png", frames=2, columns=2,
                            width=64, height=48)
    assert png_size(out) == (128, 48)
    assert (duet_model.geom_matid >= 0).sum() > 0 and duet_model.geom_rgba.shape[1] == 4   # model given back


def test_the_legend_is_drawn_below_the_caption(duet_model, offscreen_gl):
    """The caption's legend lines reach the picture: below the box of the song, tempo and F1, in its left part."""
    from types import SimpleNamespace

    from dexguitar.perform.play import caption
    from dexguitar.perform.video import SceneRenderer
    text = caption(SimpleNamespace(title="Song", tempo=100), 0, float("nan"))
    q = duet_model.key_qpos[0]
    with SceneRenderer(duet_model, 320, 180) as r:
        bare, top, full = r.frame(q), r.frame(q, caption="\n".join(text.splitlines()[:3])), r.frame(q, caption=text)
    changed = lambda a, b: np.abs(a.astype(int) - b.astype(int)).sum(-1) > 30            # noqa: E731
    box = np.nonzero(changed(bare, top))[0].max()            # the last line of the three-line caption's box
    rows, cols = np.nonzero(changed(top, full))
    assert np.sum(rows > box + 10) > 100 and cols.max() < 240


def test_render_video_needs_ffmpeg_or_says_so(tmp_path, duet_model, monkeypatch):
    import builtins

    from dexguitar.perform import video as V
    real = builtins.__import__

    def no_ffmpeg(name, *a, **k):
        if name == "imageio_ffmpeg":
            raise ImportError(name)
        return real(name, *a, **k)
    monkeypatch.setattr(builtins, "__import__", no_ffmpeg)
    q = duet_model.key_qpos[:1]
    with pytest.raises(RuntimeError, match="pip install imageio-ffmpeg"):
        V.render_video(duet_model, q, None, tmp_path / "v.mp4")


def test_render_video_with_audio(tmp_path, duet_model, offscreen_gl):
    import re
    import subprocess

    import imageio_ffmpeg                                  # installed by the setup (the `video` extra): no skip

    from dexguitar.perform import video as V
    wav = A.write_wav(tmp_path / "a.wav", A.render_audio([(0.0, 1, 0)], 0.1), FS)
    q = np.tile(duet_model.key_qpos[0], (7, 1))           # 7 / 60 s of picture, longer than the 0.1 s of sound
    out = V.render_video(duet_model, q, np.tile(C.GREEN, (7, 6, 1)), tmp_path / "v.mp4", fps=60, audio=wav,
                         width=64, height=48, camera="closeup", captions=["a caption"] * 7)
    probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(out)], check=False,
                           capture_output=True, text=True).stderr
    assert "Video: h264" in probe and "Audio: aac" in probe
    count = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-i", str(out), "-map", "0:v", "-f", "null", "-"],
                           check=False, capture_output=True, text=True).stderr
    assert re.findall(r"frame=\s*(\d+)", count)[-1] == "7"       # every frame, the last one too
