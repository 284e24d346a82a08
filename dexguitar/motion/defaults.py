"""The shipped default reference motions, and the tool that makes them (`python -m dexguitar.motion.defaults`).

Why our own clips: motion imitation needs reference link states for both hands, and the authors' motion-capture data
may not be redistributed. These clips are made here, deterministically, by the IK planner
(`dexguitar.planner`) playing procedural exercises through MuJoCo C physics:

* left, "scale practice" (`left_scale_practice.npz`, ~40 s): after a 1/8 rest, two-octave major scales in four
  one-finger-per-fret boxes along the neck (G at fret 2, C at 7, F at 12, E at 16), each up and back down in 1/8
  notes at 100 BPM (18 frames a note), one note per string and fret: the fingers press successive frets, curled,
  with the thumb behind the neck, and the hand shifts position between boxes (index sliding along string 6).
* right, "picking" (`right_picking.npz`, ~15 s): single-string alternate picking (strings 1, 3, 5), a run over
  neighbouring strings 6 -> 1 -> 6, full strums down and up, and partial strums (strings 1-3, 4-6, 2-4, 3-5).

How: the song becomes a `Timeline`, then `planner.Notes`; the scripted hand plans the desired joint trajectory
(IK on fingertip / pick targets with MuJoCo kinematics, minimum-jerk between keyframes), and `planner.Tracker`
turns it into PD targets and steps `mujoco.mj_step` 4 substeps per 60 Hz frame on the env's one-hand scene. The
simulated qpos after every frame (the first frame is the home pose) is the clip: a physically feasible motion of
our own hand model, stored as float32 at 60 fps.
"""
from __future__ import annotations

import functools
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar.motion import kinematics as K
from dexguitar import planner as PL
from dexguitar.motion.format import Motion, load, save
from dexguitar.music import procedural
from dexguitar.music import timeline as TL
from dexguitar.music.song import MUTE, OPEN, Song, make_note
from dexguitar.world import detect
from dexguitar.world import scene as S

CLIPS_DIR = Path(__file__).resolve().parent / "clips"
CLIPS = {"left": "left_scale_practice.npz", "right": "right_picking.npz"}
FPS = 60
TEMPO = 100
# (root pitch class, box start fret) of the scale boxes: G, C, F, E major along the neck.
LEFT_BOXES = ((7, 2), (0, 7), (5, 12), (4, 16))


def _single(string: int, fret: int, duration="1/8"):
    frets = [MUTE] * 6
    frets[string - 1] = fret
    return make_note(duration, frets)


def _strings(lo: int, hi: int, duration):
    return make_note(duration, [OPEN if lo <= s <= hi else MUTE for s in range(1, 7)])


def left_song() -> Song:
    """Scale practice: each box's two-octave major scale up then down, 1/8 notes at 100 BPM (~40 s)."""
    notes = [make_note("1/8", [MUTE] * 6)]                  # a rest: time to reach the first position
    for root, start in LEFT_BOXES:
        run = procedural.scale_run(start, root, "major")
        notes += [_single(s, f) for s, f in run + run[-2::-1]]
    return Song(TEMPO, tuple(notes), "left scale practice")


def right_song() -> Song:
    """Picking practice on open strings (~15 s at 100 BPM)."""
    notes = [make_note("1/8", [MUTE] * 6)]
    for s in (1, 3, 5):                                      # alternate picking on one string
        notes += [_single(s, OPEN)] * 4
    notes += [_single(s, OPEN) for s in (6, 5, 4, 3, 2, 1, 2, 3, 4, 5, 6)]     # neighbouring strings
    notes += [_strings(1, 6, "1/4")] * 4                     # full strums, down and up
    for lo, hi in ((1, 3), (4, 6), (2, 4), (3, 5)):          # partial strums
        notes += [_strings(lo, hi, "1/4")] * 2
    notes += [_single(s, OPEN) for s in (4, 3, 2, 1, 2, 3)]
    return Song(TEMPO, tuple(notes), "right picking practice")


SONGS = {"left": left_song, "right": right_song}


def _notes(song: Song) -> PL.Notes:
    tl = TL.from_song(song)
    n = int(tl.n_notes)
    return PL.Notes(np.asarray(tl.left)[:n].astype(int), np.asarray(tl.pick)[:n].astype(bool),
                    np.asarray(tl.onset)[:n + 1].astype(int))


def record(hand: str, song: Song | None = None) -> Motion:
    """Play `song` (default: the hand's practice song) with the scripted hand through MuJoCo C physics and return
    the simulated joint values at 60 fps."""
    song = song or SONGS[hand]()
    notes = _notes(song)
    player = PL.ScriptedLeft() if hand == "left" else PL.ScriptedRight()
    q_des = player.desired(notes)
    tracker = PL.Tracker(hand)
    _, q = tracker.track(q_des)
    qadr = np.asarray(S.hand_index(tracker.model, hand).qpos)
    return Motion(hand, FPS, q[:, qadr], name=song.title)


def clip_path(hand: str) -> Path:
    if hand not in CLIPS:
        raise ValueError(f"hand must be 'left' or 'right', got {hand!r}")
    return CLIPS_DIR / CLIPS[hand]


@functools.lru_cache(maxsize=2)
def _load_cached(hand: str) -> Motion:
    return load(clip_path(hand))


def default_motion(hand: str) -> Motion:
    """The shipped default clip of that hand (float32 qpos, 60 fps)."""
    m = _load_cached(hand)
    return m.replace(qpos=m.qpos.copy())


def press_report(motion: Motion, song: Song | None = None) -> dict:
    """How well a left-hand motion holds its song's notes: per frame the frets detected (`world.detect`) on FK
    finger segments, compared with the note sounding at that frame (2nd half of each note: after the press)."""
    song = song or left_song()
    notes = _notes(song)
    segs = K.finger_segments(motion)
    pressed = np.asarray(jax.jit(jax.vmap(detect.pressed_frets))(jnp.asarray(segs, jnp.float32)))
    held = total = 0
    for i in range(notes.n):
        goal = notes.left[i]
        if not (goal > 0).any():
            continue
        a, b = notes.onset[i], notes.onset[i + 1]
        for t in range((a + b) // 2 + 1, min(b + 1, len(pressed))):   # frame t: the state after step t - 1
            total += 1
            held += bool(np.all(np.where(goal > 0, pressed[t] == goal, True)))
    one = np.mean((pressed > 0).sum(1) == 1)
    return {"frames_holding_the_note": held / max(total, 1), "frames_pressing_one_string": float(one)}


def pick_report(motion: Motion, song: Song | None = None) -> dict:
    """Strings crossed by the pick along the FK path, against the strings the song picks."""
    song = song or right_song()
    notes = _notes(song)
    p = K.pick_positions(motion)
    crossed = np.array([np.asarray(detect.pick_crossings(jnp.asarray(p[t - 1]), jnp.asarray(p[t])).picked)
                        for t in range(1, len(p))])
    want = int(notes.pick.sum())
    got = int(crossed.sum())
    ok = 0
    for i in range(notes.n):
        a, b = notes.onset[i], notes.onset[i + 1]
        ok += int(np.all(crossed[a:b].any(0) == notes.pick[i]))
    return {"string_crossings": got, "target_strings": want, "notes_exact": ok, "notes": notes.n}


def main():
    CLIPS_DIR.mkdir(parents=True, exist_ok=True)
    for hand in ("left", "right"):
        t0 = time.time()
        motion = record(hand)
        path = save(motion, clip_path(hand))
        loaded = load(path)
        report = press_report(loaded) if hand == "left" else pick_report(loaded)
        print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KB): {loaded.n_frames} frames, "
              f"{loaded.seconds:.1f} s at {loaded.fps:g} fps, {time.time() - t0:.0f} s; {report}")


if __name__ == "__main__":
    main()
