"""A two-hand performance of a song: both frozen policies in the duet env, recorded, judged note by note, and turned
into a video (coloured strings, `colors.py`), a WAV (`audio.py`) and a report.

Without a synchronizer this is the paper's "before synchronization" performance: each hand's policy sees only its
own part of the duet observation and plays on its own clock, so the left hand may press late for the right hand's
pick. The player is a plain `act(obs) -> action` over the duet observation, so a synchronizer (`learn/sync.py`, which
shifts the frozen policies' latents) plugs in as `act=` with nothing else changed.

Per-note verdicts (the "both hands" rules of `metrics.py`, Sec. 6.1):
- right: every target picked once, pressed right at the pick and held for 2/3 of the note (both-hands F1 = 1);
- late: the right notes sounded (every target picked once, in its expected state, nothing else picked) but the last
  of those picks came after the first 1/3 of the note, too late to hold for 2/3 of it;
- wrong: anything else, with the reason: missed, wrong string, extra pick, picked before the press (the left hand
  got there later in the note: out of time), wrong fret, released early;
- rest: a note with nothing to play (a pick during it makes it wrong); legato notes (tie / hammer-on / pull-off /
  slide: nothing to pick) are right when the left hand's F1 is 1.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from dexguitar.perform import audio as A
from dexguitar.perform import colors as C

FPS = 60
HIST_FRAMES = 2
HAND_FEATURES = 16 * 13        # one hand's numbers in one history frame
GOAL = 35                      # one hand's goal


# ---------------------------------------------------------------------------------------------------- players

def split_obs(obs):
    """Duet observation (..., 902) = [hist (2 frames x [left 208 | right 208]) | left goal 35 | right goal 35]
    -> (left obs, right obs), each (..., 451) = [own 2 x 208 frames | own goal] as the single-hand envs build it."""
    import jax.numpy as jnp
    batch = obs.shape[:-1]
    n_hist = HIST_FRAMES * 2 * HAND_FEATURES
    hist = obs[..., :n_hist].reshape(batch + (HIST_FRAMES, 2, HAND_FEATURES))
    goal_l, goal_r = obs[..., n_hist:n_hist + GOAL], obs[..., n_hist + GOAL:n_hist + 2 * GOAL]
    left = jnp.concatenate([hist[..., 0, :].reshape(batch + (-1,)), goal_l], axis=-1)
    right = jnp.concatenate([hist[..., 1, :].reshape(batch + (-1,)), goal_r], axis=-1)
    return left, right


def joint_act(act_left, act_right):
    """The unsynchronized duet player: each hand's policy on its own part of the observation."""
    import jax.numpy as jnp

    def act(obs):
        left, right = split_obs(obs)
        return jnp.concatenate([act_left(left), act_right(right)], axis=-1)
    return act


def load_policies(left_dir, right_dir):
    """(act_left, act_right) from exported policies (or run directories), checking which hand each one plays."""
    from dexguitar.learn.run import policy_from
    out = []
    for want, directory in (("left", left_dir), ("right", right_dir)):
        act, meta = policy_from(directory)
        if meta.get("hand") not in (None, want):
            raise ValueError(f"{directory}: a policy for the {meta.get('hand')} hand, expected the {want} hand")
        out.append(act)
    return tuple(out)


# ---------------------------------------------------------------------------------------------------- recording

def play(song, act, *, seconds: float | None = None, env_config=None, key=None) -> dict:
    """Play `song` (a Song) with `act(duet obs) -> (54,) action` from its start, for the whole song or its first
    `seconds`. Returns numpy arrays per control step (`press`, `picks`, `qpos`, `song_note`, `note_end`, per-note
    scores "left"/"right"/"both"; `row`: the window row being played) plus the window rows (`goal_left`, `pick`,
    `dur`, `onset`) and `rollout_seconds` (compile included).

    Steps are mapped to window rows by the rows' durations (a sequential window is played row after row from
    step 0), not by `song_note`, so a grace rest the env may put before the song (row 0, song note -1) is handled
    whether it is there or not."""
    import jax

    from dexguitar import envs
    from dexguitar.music import timeline as TL
    from dexguitar.perform.evaluate import rollout_song
    tl = TL.from_song(song)
    env = envs.make("duet", [tl], env_config or envs.EnvConfig().evaluation())
    if not env.config.sequential:
        raise ValueError("play needs an evaluation config (EnvConfig().evaluation()): whole songs from the start")
    key = jax.random.PRNGKey(0) if key is None else key
    window = jax.device_get(env.sample_window(key, 0))      # sequential: no randomness, the rows reset() plays
    rows = int(window.n)
    dur = np.asarray(window.dur)[:rows]
    onset = np.concatenate([[0], np.cumsum(dur)])
    n = int(onset[-1])
    frames = n if seconds is None else max(1, min(n, int(round(seconds * FPS))))
    t0 = time.perf_counter()
    info, alive = jax.device_get(jax.jit(lambda k: rollout_song(env, act, 0, frames, k))(key))
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
    from dexguitar.perform.evaluate import note_scores
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
        state_ok = np.array([bool(C.in_state(goal, press[first[s]])[s]) if first[s] >= 0 else False
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
            later = all(np.any(C.in_state(goal, press[first[s]:])[:, s] if press[first[s]:].size else False)
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
    return C.rollout_colors(rec["press"], rec["picks"], rec["row"], rec["goal_left"], rec["pick"])


# ---------------------------------------------------------------------------------------------------- reports

def _fmt_frets(frets) -> str:
    return "-" if frets is None else " ".join("x" if f < 0 else str(f) for f in reversed(frets))


def format_report(report: dict) -> str:
    """A human-readable per-note table and the totals."""
    judged = sum(r["note"] >= 0 for r in report["notes"])
    lines = [f"{report['title']}: {report['seconds']:.1f} s, {judged} notes judged"]
    lines.append(f"{'#':>4s} {'frame':>6s} {'frets (6..1)':>14s} {'left':>5s} {'right':>5s} {'both':>5s}  verdict")
    for r in report["notes"]:
        if r["note"] < 0 and r["verdict"] == "rest":
            continue                                  # the env's grace rest before the song, played as a rest
        lines.append(f"{r['note']:4d} {r['onset_frame']:6d} {_fmt_frets(r['frets']):>14s} {r['left']['f1']:5.2f} "
                     f"{r['right']['f1']:5.2f} {r['both']['f1']:5.2f}  {r['verdict']}"
                     + (f" ({r['why']}; picked {r['picked'] or 'nothing'})" if r["why"] else ""))
    c, s = report["counts"], report["summary"]
    lines.append("verdicts: " + ", ".join(f"{k} {v}" for k, v in c.items()))
    lines.append("F1 " + "  ".join(f"{h} {s[h]['f1']:.3f} (P {s[h]['precision']:.3f} R {s[h]['recall']:.3f}, "
                                   f"{s[h]['notes']} notes)" for h in ("left", "right", "both")))
    return "\n".join(lines)


def perform(song, left_dir=None, right_dir=None, out_prefix="perf", *, seconds: float | None = None, act=None,
            act_left=None, act_right=None, video: bool = True, video_fps: float = 30.0, width: int = 960,
            height: int = 540, env_config=None, quiet: bool = False) -> dict:
    """Play `song` (a Song, an embedded song's name or a tab file) with both hands and write
    `<out_prefix>.mp4` (with sound; a `<out_prefix>.png` contact sheet when imageio-ffmpeg is missing or
    `video=False`), `<out_prefix>.wav` and `<out_prefix>-report.json`; print the per-note report unless `quiet`.

    The player is, in order of precedence: `act(duet obs) -> both actions` (e.g. a synchronizer), or
    `act_left` / `act_right` (each on its own observation), or the policies exported in `left_dir` / `right_dir`.
    Returns the report dict (notes, verdict counts, F1 per hand, output paths, timings)."""
    from dexguitar.music import load_song
    if not hasattr(song, "notes"):
        song = load_song(song)
    if act is None:
        if act_left is None or act_right is None:
            if left_dir is None or right_dir is None:
                raise ValueError("give act=, or act_left= and act_right=, or left_dir and right_dir")
            act_left, act_right = load_policies(left_dir, right_dir)
        act = joint_act(act_left, act_right)
    out_prefix = Path(out_prefix)
    if out_prefix.suffix.lower() in (".mp4", ".wav", ".png", ".json"):
        out_prefix = out_prefix.with_suffix("")
    out_prefix.parent.mkdir(parents=True, exist_ok=True)
    timings = {}

    rec = play(song, act, seconds=seconds, env_config=env_config)
    timings["rollout_s"] = rec["rollout_seconds"]
    t = time.perf_counter()
    rows = note_verdicts(rec, song)
    from dexguitar.perform.evaluate import summarize
    summary = summarize(rows, ("left", "right", "both"))
    colors = render_colors(rec)
    length = rec["frames"] / FPS
    events = A.events_from_info(rec, FPS)
    wav = A.write_wav(out_prefix.with_suffix(".wav"), A.render_audio(events, length))
    timings["audio_s"] = time.perf_counter() - t

    t = time.perf_counter()
    from dexguitar.perform import video as V
    from dexguitar.world import scene as S
    model = S.build_spec("duet", mirror=bool(env_config and env_config.mirror), visual=True).compile()
    stride = max(1, int(round(FPS / video_fps)))
    if video and V.have_ffmpeg():
        picture = V.render_video(model, rec["qpos"][::stride], colors[::stride], out_prefix.with_suffix(".mp4"),
                                 fps=FPS / stride, audio=wav, width=width, height=height)
    else:
        if video and not quiet:
            print("imageio-ffmpeg is not installed (pip install imageio-ffmpeg): writing a PNG contact sheet",
                  file=sys.stderr)
        picture = V.render_frames_png(model, rec["qpos"], colors, out_prefix.with_suffix(".png"), frames=12)
    timings["render_s"] = time.perf_counter() - t

    counts = {k: sum(r["verdict"] == k for r in rows if r["note"] >= 0 or k == "wrong")
              for k in ("right", "late", "wrong", "rest")}
    report = {"title": song.title, "seconds": length, "frames": rec["frames"], "counts": counts,
              "summary": summary, "notes": rows, "events": len(events),
              "files": {"video" if picture.suffix == ".mp4" else "frames": str(picture), "audio": str(wav),
                        "report": str(out_prefix) + "-report.json"},
              "timings": {k: round(v, 2) for k, v in timings.items()}}
    Path(report["files"]["report"]).write_text(json.dumps(report, indent=1))
    if not quiet:
        print(format_report(report))
        print("wrote " + ", ".join(report["files"].values()))
    return report


def main(argv=None) -> int:
    """`dexguitar play (--ckpt SYNC | --left L --right R) --song S --out perf [--seconds 10] [--frames-only]`."""
    p = argparse.ArgumentParser(prog="dexguitar play", description="Both hands play a song: video, audio, report.")
    p.add_argument("--ckpt", help="a synchronizer (`dexguitar sync` run or its policy/): both hands, synchronized")
    p.add_argument("--left", help="left-hand policy (exported policy or run directory), without a synchronizer")
    p.add_argument("--right", help="right-hand policy")
    p.add_argument("--unsynchronized", action="store_true", help="with --ckpt: its frozen policies alone")
    p.add_argument("--song", required=True, help="embedded song name or tab file")
    p.add_argument("--out", default="perf", help="output prefix: OUT.mp4 (or .png), OUT.wav, OUT-report.json")
    p.add_argument("--seconds", type=float, default=None, help="play only the first seconds")
    p.add_argument("--frames-only", action="store_true", help="a PNG contact sheet instead of the video")
    p.add_argument("--fps", type=float, default=30.0, help="video frame rate (the simulation runs at 60)")
    p.add_argument("--size", default="960x540", help="video size WxH")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    args = p.parse_args(argv)
    if bool(args.ckpt) == bool(args.left or args.right) or (not args.ckpt and not (args.left and args.right)):
        p.error("give either --ckpt SYNC or both --left and --right")
    act = None
    if args.ckpt:
        from dexguitar.learn.run import policy_from
        act, meta = policy_from(args.ckpt, synchronized=not args.unsynchronized)
        if meta.get("kind") != "synchronizer":
            p.error(f"--ckpt {args.ckpt}: a {meta.get('hand')} hand policy, not a synchronizer (use --left/--right)")
    width, height = (int(v) for v in args.size.lower().split("x"))
    report = perform(args.song, args.left, args.right, args.out, seconds=args.seconds, act=act,
                     video=not args.frames_only, video_fps=args.fps, width=width, height=height, quiet=args.json)
    if args.json:
        print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
