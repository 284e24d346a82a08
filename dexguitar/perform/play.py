"""A two-hand performance of a song: both frozen policies in the duet env, recorded, judged note by note, and turned
into a video (coloured strings, `colors.py`), a WAV (`audio.py`) and a report.

Without a synchronizer (`pair`) this is the paper's "before synchronization" performance: each hand's policy sees only
its own part of the duet observation and plays on its own clock, so the left hand may press late for the right hand's
pick. Both players act through `learn.policy` (a pair is a synchronizer with a zero output layer).

Per-note verdicts (the "both hands" rules of `world/scoring.py`, Sec. 6.1):
- right: every target picked once, pressed right at the pick and held for 2/3 of the note (both-hands F1 = 1);
- late: the right notes sounded (every target picked once, in its expected state, nothing else picked) but the last
  of those picks came after the first 1/3 of the note, too late to hold for 2/3 of it;
- wrong: anything else, with the reason: missed, wrong string, extra pick, picked before the press (the left hand
  got there later in the note: out of time), wrong fret, released early;
- rest: a note with nothing to play (a pick during it makes it wrong); legato notes (tie / hammer-on / pull-off /
  slide: nothing to pick) are right when the left hand's F1 is 1.
"""
from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.learn import policy as PO
from dexguitar.motion import export as EX
from dexguitar.motion.glcheck import INSTALL, NoGL
from dexguitar.music import load_song
from dexguitar.music import timeline as TL
from dexguitar.perform import audio, colors
from dexguitar.perform import video as V
from dexguitar.perform.evaluate import dumps, note_scores, rollout_song, summarize
from dexguitar.world import stage

FPS = 60
# The recording's XLA options on a CPU: the older loop emitters compile its long loop of the duet env and the policies
# a third faster than the default fusion emitters (the demo's rollout: 9.5 s instead of 14.1 s on 2 cores), and it
# runs as fast, with the same report. Evaluation keeps the defaults: the float sums differ in the last bits, which
# can move a borderline note and its F1 (`evaluate` on the demo's song: both hands 0.951 -> 0.956).
CPU_COMPILE_OPTIONS = {"xla_cpu_use_fusion_emitters": False}


# ---------------------------------------------------------------------------------------------------- players

def pair(left_dir, right_dir):
    """(params, spec) of two exported single-hand policies playing together without a synchronizer: a synchronizer
    whose output layer is zero (`policy.unsynchronized`), so the pair plays exactly as each hand alone on its own
    slice of the duet observation, through the one way to act."""
    (left, lmeta), (right, rmeta) = PO.load_pair(left_dir, right_dir)
    one = PO.PolicySpec.from_meta(lmeta).layout
    layout = dataclasses.replace(one, roles=("left", "right"))          # the duet: the two hands side by side
    PO.check_pair(lmeta, rmeta, layout, where=(str(left_dir), str(right_dir)))
    sync, norm = PO.init_synchronizer(jax.random.PRNGKey(0), left, right, layout)
    params = {"policy": sync, "obs_norm": norm, "frozen": {"left": left, "right": right}}
    lspec, rspec = PO.PolicySpec.from_meta(lmeta), PO.PolicySpec.from_meta(rmeta)
    return PO.unsynchronized(params), PO.PolicySpec("synchronizer", "duet", 2 * lmeta["action_size"], layout,
                                                    lspec.feedforward, lspec.scale, rspec.right_feedforward)


# ---------------------------------------------------------------------------------------------------- recording

def play(song, params, spec: PO.PolicySpec, *, seconds: float | None = None, env_config=None, key=None) -> dict:
    """Play `song` (a Song) with a duet policy (params, spec) from its start, for the whole song or its first
    `seconds`. Returns numpy arrays per control step (`press`, `picks`, `qpos`, `song_note`, `note_end`, per-note
    scores "left"/"right"/"both"; `row`: the window row being played) plus the window rows (`goal_left`, `pick`,
    `dur`, `onset`) and `rollout_seconds` (compile included). The parameters are an argument of the compiled
    rollout, so a later run of the same song loads it from the compilation cache.

    Steps are mapped to window rows by the rows' durations (a sequential window is played row after row from
    step 0), not by `song_note`, so a grace rest the env may put before the song (row 0, song note -1) is handled
    whether it is there or not."""
    config = spec.env_config(env_config or envs.EnvConfig().evaluation()).sized(1)
    env = envs.make("duet", [TL.from_song(song)], config)
    if not env.config.sequential:
        raise ValueError("play needs an evaluation config (EnvConfig().evaluation()): whole songs from the start")
    key = jax.random.PRNGKey(0) if key is None else key
    # sequential: no randomness, the rows reset() plays (one small program rather than dozens of eager ones)
    window = jax.device_get(jax.jit(env.sample_window, static_argnums=1)(key, 0))
    rows = int(window.n)
    dur = np.asarray(window.dur)[:rows]
    onset = np.concatenate([[0], np.cumsum(dur)])
    n = int(onset[-1])
    frames = n if seconds is None else max(1, min(n, int(round(seconds * FPS))))
    act = PO.act_fn(spec, deterministic=True)
    t0 = time.perf_counter()
    params = jax.tree.map(jnp.asarray, params)
    options = CPU_COMPILE_OPTIONS if jax.default_backend() == "cpu" else None
    record = jax.jit(lambda p, k: rollout_song(env, lambda obs: act(p, obs)[0], 0, frames, k))
    info, alive = jax.device_get(record.lower(params, key).compile(options)(params, key))
    elapsed = time.perf_counter() - t0
    keep = int(np.sum(alive))
    rec = {k: np.asarray(v)[:keep] for k, v in info.items() if k != "links"}
    rec.update(goal_left=np.asarray(window.left)[:rows], pick=np.asarray(window.pick)[:rows], dur=dur, onset=onset,
               row=np.searchsorted(onset, np.arange(keep), side="right") - 1, rollout_seconds=elapsed, frames=keep)
    return rec


def note_verdicts(rec: dict, song) -> list[dict]:
    """One row per note finished in the recording: the note's index, frets, per-hand precision/recall/F1 (the
    env's own per-note scores) and a verdict (see the module docstring) with its reason and the frame of its first
    pick within the note."""
    rows = note_scores(rec, song, ("left", "right", "both"))
    for row in rows:
        i = row["note"]
        w = int(np.searchsorted(rec["onset"], row["frame"], side="right") - 1)      # the window row that ended
        a, dur = int(rec["onset"][w]), int(rec["dur"][w])
        goal, targets = rec["goal_left"][w], rec["pick"][w].astype(bool)
        picks = rec["picks"][a:a + dur].astype(bool)
        press = rec["press"][a:a + dur]
        count = picks.sum(0)
        first = np.where(count > 0, np.argmax(picks, axis=0), -1)
        state_ok = np.array([bool(colors.in_state(goal, press[first[s]])[s]) if first[s] >= 0 else False
                             for s in range(6)])
        row["onset_frame"], row["frames"] = a, dur
        row["first_pick"] = int(first[first >= 0].min()) if np.any(first >= 0) else None
        row["picked"] = [int(i) + 1 for i in np.flatnonzero(count) for _ in range(int(count[i]))]
        if not targets.any():
            note = song.notes[i] if 0 <= i < len(song.notes) else None       # i = -1: the grace rest
            if note is None or note.is_rest:
                verdict, why = ("rest", "") if not count.any() else ("wrong", "extra pick")
            else:
                ok = row["left"]["f1"] >= 1.0 and not count.any()
                verdict, why = ("right", "legato") if ok else ("wrong", "legato" if not count.any() else "extra pick")
        elif row["both"]["f1"] >= 1.0:
            verdict, why = "right", ""
        elif np.any(targets & (count == 0)):
            verdict, why = "wrong", "wrong string" if np.any(~targets & (count > 0)) else "missed"
        elif np.any(~targets & (count > 0)) or np.any(count > 1):
            verdict, why = "wrong", "extra pick"
        elif not np.all(state_ok[targets]):
            # pressed right later in the note: the hands were out of time (what a synchronizer fixes)
            bad = targets & ~state_ok
            later = all(np.any(colors.in_state(goal, press[first[s]:])[:, s] if press[first[s]:].size else False)
                        for s in np.flatnonzero(bad))
            verdict, why = "wrong", "picked before the press" if later else "wrong fret"
        elif 3 * int(first[targets].max()) >= dur:
            verdict, why = "late", f"picked at frame {int(first[targets].max())} of {dur}"
        else:
            verdict, why = "wrong", "released early"
        row["verdict"], row["why"] = verdict, why
    return rows


def render_colors(rec: dict) -> np.ndarray:
    """(T, 6, 4) string colours of a recording (`colors.rollout_colors` on the per-step note index)."""
    return colors.rollout_colors(rec["press"], rec["picks"], rec["row"], rec["goal_left"], rec["pick"])


# ---------------------------------------------------------------------------------------------------- reports

def _count(n: int, word: str) -> str:
    """'1 note', '2 notes'."""
    return f"{n} {word}{'' if n == 1 else 's'}"


def _fmt_frets(frets) -> str:
    return "-" if frets is None else " ".join("x" if f < 0 else str(f) for f in frets)


def report_note(row: dict) -> dict:
    """A per-note row as the report holds it: its frets as `frets_6_to_1`, string 6 (low E) first, the order of the
    table and of the chord names in the summary (a row of `note_verdicts` has them string 1 first, as a Song)."""
    return {("frets_6_to_1" if k == "frets" else k): (v[::-1] if k == "frets" and v is not None else v)
            for k, v in row.items()}


def format_report(report: dict) -> str:
    """A human-readable per-note table and the totals. The header counts the notes and the rests judged apart (a rest
    played cleanly is in no hand's F1), and the count-in before the song where something happened in it; each F1 is
    the mean over the notes where that hand had something to do or did something, as `summarize` counts them."""
    song_rows = [r for r in report["notes"] if r["note"] >= 0]
    rests = sum(bool(r["rest"]) for r in song_rows)
    parts = [_count(len(song_rows) - rests, "note")] + [_count(rests, "rest")] * (rests > 0)
    parts += ["the count-in"] * (len(song_rows) < len(report["notes"]))
    judged = parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]
    lines = [f"{report['title']}: {report['seconds']:.1f} s, {judged} judged"]
    lines.append(f"{'#':>4s} {'frame':>6s} {'frets (6..1)':>14s} {'left':>5s} {'right':>5s} {'both':>5s}  verdict")
    for r in report["notes"]:
        if r["note"] < 0 and r["verdict"] == "rest":
            continue                                  # the env's grace rest before the song, played as a rest
        lines.append(f"{r['note']:4d} {r['onset_frame']:6d} {_fmt_frets(r['frets_6_to_1']):>14s} "
                     f"{r['left']['f1']:5.2f} {r['right']['f1']:5.2f} {r['both']['f1']:5.2f}  {r['verdict']}"
                     + (f" ({r['why']}; picked {r['picked'] or 'nothing'})" if r["why"] else ""))
    c, s = report["counts"], report["summary"]
    lines.append("verdicts: " + ", ".join(f"{k} {v}" for k, v in c.items()))
    lines.append("F1, the mean over the notes each hand had to play or played:")
    lines += [f"  {h:5s} {s[h]['f1']:.3f} (P {s[h]['precision']:.3f} R {s[h]['recall']:.3f}, "
              f"{_count(s[h]['notes'], 'note')})" for h in ("left", "right", "both")]
    return "\n".join(lines)


def running_f1(rows: list[dict], n_frames: int, hand: str = "both") -> tuple[np.ndarray, np.ndarray]:
    """Per recording frame: how many notes are judged so far and their F1 (`summarize`: the mean over the notes that
    concern `hand`; NaN before the first), as the video's caption shows them. The last frame's numbers are the
    report's."""
    notes, f1 = np.zeros(n_frames, int), np.full(n_frames, np.nan)
    rows = sorted(rows, key=lambda r: r["frame"])
    for k, row in enumerate(rows):
        s = summarize(rows[:k + 1], (hand,))[hand]
        notes[row["frame"]:], f1[row["frame"]:] = s["notes"], s["f1"]
    return notes, f1


def caption(song, notes: int, f1: float) -> str:
    """The on-screen caption: the song, its tempo, the both-hands F1 of the notes judged so far, and the legend of
    the string colours (`colors.legend`)."""
    score = f"{f1:.3f} ({_count(notes, 'note')})" if notes else "-"
    return f"{song.title or 'untitled'}\n{song.tempo:g} bpm\nF1 both hands: {score}\n{colors.legend()}"


def perform(song, params, spec: PO.PolicySpec, out_prefix="perf", *, seconds: float | None = None,
            video: bool = True, video_fps: float = 30.0, width: int = 1280, height: int = 720, camera: str = "front",
            captions: bool = False, env_config=None, quiet: bool = False, motion: bool = False) -> dict:
    """Play `song` (a Song, an embedded song's name or a tab file) with a duet policy (a synchronizer's params and
    spec from `policy.load`, or `pair(left, right)`) and write `<out_prefix>.mp4` (with sound; a
    `<out_prefix>.png` contact sheet when imageio-ffmpeg is missing or `video=False`), `<out_prefix>.wav` and
    `<out_prefix>-report.json`; print the per-note report unless `quiet`. `camera`: "front" (both hands) or
    "closeup" (the fretting hand); `captions`: the song, tempo, running F1 and the legend of the string colours in
    the picture. The report's notes give frets as `frets_6_to_1` (string 6 first, as its table). Without an offscreen
    OpenGL there is no picture: the rest is written and one line says what to install. `motion`: also the hands'
    motions, `<out_prefix>-left.npz` and `<out_prefix>-right.npz` (60 Hz), and `<out_prefix>.bvh` of both hands for
    animation tools (`motion.export`).
    Returns the report dict (notes, verdict counts, F1 per hand, output paths, timings)."""
    if not hasattr(song, "notes"):
        song = load_song(song)
    out_prefix = Path(out_prefix)
    if out_prefix.suffix.lower() in (".mp4", ".wav", ".png", ".json"):
        out_prefix = out_prefix.with_suffix("")
    out_prefix.parent.mkdir(parents=True, exist_ok=True)
    timings = {}

    rec = play(song, params, spec, seconds=seconds, env_config=env_config)
    timings["rollout_s"] = rec["rollout_seconds"]
    t = time.perf_counter()
    rows = note_verdicts(rec, song)
    summary = summarize(rows, ("left", "right", "both"))
    string_colors = render_colors(rec)
    length = rec["frames"] / FPS
    events = audio.events_from_info(rec, FPS)
    wav = audio.write_wav(out_prefix.with_suffix(".wav"), audio.render_audio(events, length))
    timings["audio_s"] = time.perf_counter() - t
    motions = EX.export_performance(out_prefix, rec["qpos"], FPS, mirror=bool(env_config and env_config.mirror),
                                    name=song.title or "") if motion else {}

    t = time.perf_counter()
    model = stage.stage_model("duet", mirror=bool(env_config and env_config.mirror))
    texts = [caption(song, n, f) for n, f in zip(*running_f1(rows, rec["frames"]))] if captions else None
    stride = max(1, int(round(FPS / video_fps)))
    # a video frame shows `stride` recording frames; its caption counts the notes judged by the last of them, so
    # the video ends on the report's numbers
    last_shown = np.minimum(np.arange(0, rec["frames"], stride) + stride - 1, rec["frames"] - 1)
    try:
        if video and V.have_ffmpeg():
            picture = V.render_video(model, rec["qpos"][::stride], string_colors[::stride],
                                     out_prefix.with_suffix(".mp4"), fps=FPS / stride, audio=wav, width=width,
                                     height=height, camera=camera,
                                     captions=None if texts is None else [texts[i] for i in last_shown])
        else:
            if video and not quiet:
                print("imageio-ffmpeg is not installed (pip install imageio-ffmpeg): writing a PNG contact sheet",
                      file=sys.stderr)
            picture = V.render_frames_png(model, rec["qpos"], string_colors, out_prefix.with_suffix(".png"),
                                          frames=12, camera=camera, captions=texts, fps=FPS)
    except NoGL:
        picture = None
        print(f"no offscreen OpenGL: {INSTALL}, then run again for the video", file=sys.stderr)
    timings["render_s"] = time.perf_counter() - t

    counts = {k: sum(r["verdict"] == k for r in rows if r["note"] >= 0 or k == "wrong")
              for k in ("right", "late", "wrong", "rest")}
    files = {} if picture is None else {"video" if picture.suffix == ".mp4" else "frames": str(picture)}
    files.update(audio=str(wav), report=str(out_prefix) + "-report.json")
    files.update({kind: str(path) for kind, path in motions.items()})
    report = {"title": song.title, "seconds": length, "frames": rec["frames"], "counts": counts,
              "summary": summary, "notes": [report_note(r) for r in rows], "events": len(events), "files": files,
              "timings": {k: round(v, 2) for k, v in timings.items()}}
    Path(report["files"]["report"]).write_text(dumps(report, indent=1))
    if not quiet:
        print(format_report(report))
        print("wrote " + ", ".join(report["files"].values()))
    return report
