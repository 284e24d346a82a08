"""The scripted player and its F1 table: the IK planner (`dexguitar.planner`, no learning) plays songs through
the envs (`ScriptedPlayer`), scored by the envs themselves: the embedded single-note songs
(`docs/results.md`) or any tabs, e.g. the authors' songs.

Run `python -m dexguitar.perform.scripted [--envs left,right,duet] [--songs a,b | --tabs FILE_OR_FOLDER ...]`.
"""
from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs
from dexguitar.world import scoring
from dexguitar.planner import plans as FF
from dexguitar.planner import Notes, ScriptedLeft, ScriptedRight, Tracker
from dexguitar.music import library
from dexguitar.music import timeline as TL
from dexguitar.world import hands as H

SCORE_FIELDS = ("precision", "recall", "f1", "tp", "predicted", "targets")
# A rollout's actions are padded to a power of two steps, at least this many, and its songs to a power of two notes
# (`timeline.batch`), so that most songs play one program.
MIN_STEPS = 512
# The compiled rollouts of this process, one per env, song capacities and step capacity (`ScriptedPlayer.rollout`).
_ROLLOUTS: dict = {}


class ScriptedPlayer:
    """Plans and plays songs of an env's batch with the scripted hands of its roles (left, right or both).

    Each hand is planned and tracked in its own one-hand scene: the hands never touch each other, so the duet's
    dynamics are the two hands' side by side and the duet action is the two plans concatenated (role order).
    The left-handed player's scene (`EnvConfig.mirror`) is the exact mirror image of the right-handed one (no
    gravity, neck and body symmetric in x), so its actions are the right-handed plan mirrored joint by joint.
    """

    def __init__(self, env):
        self.env = env
        self.roles = env.roles
        self.left = ScriptedLeft()                         # its kinematics judge when the left hand is ready
        self.right = ScriptedRight()
        self.tracker = Tracker("right") if "right" in self.roles else None
        self.flip = {r: H.mirror_qpos(np.ones(H.N_DOF), r) if env.config.mirror else np.ones(H.N_DOF)
                     for r in self.roles}

    def plan(self, window) -> np.ndarray:
        """(frames, action_size) env actions playing `window` (a `Window`, or `Notes`) from the home pose."""
        return self.plans([window])[0]

    def plans(self, windows) -> list[np.ndarray]:
        """`plan` of each window. The left hand is planned in worker processes with one BLAS thread
        (`planner.plans.plan_all`), as the env's feedforward is, so a table made here plays the plans a residual
        policy is given (in the 15 official songs' table, plans made in this process with 2 BLAS threads scored
        `sonata_in_f_major_ms84_no14` 0.928, one-thread plans 0.900). With both hands the right hand crosses each
        note's strings only once the simulated left hand holds the note (the duet's strict gate counts an earlier
        pick as wrong)."""
        notes = [w if isinstance(w, Notes) else Notes.from_window(w) for w in windows]
        left = (FF.plan_all([(n.left, n.pick, n.onset) for n in notes], log=lambda m: None)
                if "left" in self.roles else [None] * len(notes))
        out = []
        for n, planned in zip(notes, left):
            parts, earliest = {}, None
            if planned is not None:
                parts["left"] = planned[0]
                earliest = self.left.timing(n, planned[1]) if self.tracker is not None else None
            if self.tracker is not None:
                ctrl, _ = self.tracker.track(self.right.desired(n, earliest))
                parts["right"] = self.tracker.to_action(ctrl)
            out.append(np.concatenate([parts[r] * self.flip[r] for r in self.roles], axis=1).astype(np.float32))
        return out

    def rollout(self, songs, actions: np.ndarray):
        """Roll the env over songs (B,) with actions (B, T, A), vmapped; returns per-step info plus reward,
        terminated and done (B, T, ...).

        The songs, re-batched to a fixed note capacity (`timeline.batch`), the actions, padded to a step capacity,
        and T are the program's arguments: every batch of as many songs that fits the capacities plays the program
        compiled for the first (a test or a table compiles one per env, not one per song), for T steps only."""
        env, n, T = self.env, len(songs), actions.shape[1]
        picked = [jax.tree.map(lambda x: np.asarray(x)[int(i)], env.songs) for i in songs]
        batch = TL.batch(picked, songs=n)                          # no empty rows: each costs as much as a song
        steps = TL.capacity(T, MIN_STEPS)
        acts = np.zeros((n, steps, actions.shape[2]), np.float32)
        acts[:, :T] = actions
        key = (type(env).__name__, type(env.base).__name__, env.config, str(env.base.mjx_model.impl),
               str(jax.tree.map(lambda x: (x.shape, str(x.dtype)), batch)), steps)
        if key not in _ROLLOUTS:
            def one(songs_, song, acts_, length):
                bound = env.bind(songs_)
                state = bound.reset(jax.random.PRNGKey(0), song=song)

                def record(s):
                    return dict(s.info, reward=s.reward, terminated=s.terminated, done=s.done)
                out = jax.tree.map(lambda x: jnp.zeros((steps,) + x.shape, x.dtype), record(state))

                def body(carry):
                    t, s, out = carry
                    s = bound.step(s, acts_[t])
                    return t + 1, s, jax.tree.map(lambda o, v: o.at[t].set(v), out, record(s))
                return jax.lax.while_loop(lambda c: c[0] < length, body, (jnp.int32(0), state, out))[2]
            _ROLLOUTS[key] = jax.jit(jax.vmap(one, in_axes=(None, 0, 0, None)))
        info = _ROLLOUTS[key](batch, jnp.arange(n, dtype=jnp.int32), jnp.asarray(acts), jnp.int32(T))
        return jax.tree.map(lambda x: np.asarray(x)[:, :T], info)

    def play(self, songs=0) -> list[dict] | dict:
        """Plan and play song index(es) of the env's batch. Per song: {"frames", "notes", "plan_s", "roll_s",
        per hand (left / right / both): {"f1", "precision", "recall" (means over notes), "per_note" (n, 6)}}."""
        single = np.ndim(songs) == 0
        songs = np.atleast_1d(songs)
        t0 = time.time()
        windows = [self.env.sample_window(jax.random.PRNGKey(0), int(i)) for i in songs]
        plans = self.plans(windows)
        plan_s = (time.time() - t0) / len(songs)
        out = [{"frames": len(p), "notes": int(w.n) - 1, "plan_s": plan_s} for p, w in zip(plans, windows)]  # no rest
        T = max(len(p) for p in plans)
        acts = np.stack([np.concatenate([p, np.repeat(p[-1:], T - len(p), 0)]) for p in plans])
        t0 = time.time()
        info = self.rollout(songs, acts)
        roll = time.time() - t0
        hands = [h for h in ("left", "right", "both") if h in self.roles or (h == "both" and len(self.roles) == 2)]
        for b, res in enumerate(out):
            end = info["note_end"][b, :res["frames"]] & (info["song_note"][b, :res["frames"]] >= 0)  # song notes
            res["roll_s"] = roll
            for h in hands:
                per = info[h][b, :res["frames"]][end]
                if h == "both":     # the end of note k+1 holds note k's final verdict (scoring.close)
                    per = scoring.per_note_both(per, info["both_now"][b, :res["frames"]][end])
                res[h] = {"per_note": per, **{k: float(per[:, j].mean()) if len(per) else float("nan")
                                              for j, k in enumerate(SCORE_FIELDS[:3])}}
            res["closed"] = int(end.sum())
            term = np.flatnonzero(info["terminated"][b, :res["frames"]])
            res["terminated_at"] = int(term[0]) if len(term) else None       # a failure would end the episode
            res["reward"] = info["reward"][b, :res["frames"]]
        return out[0] if single else out


SINGLE_NOTE_SONGS = ("ode_to_joy", "twinkle", "c_major_scale", "greensleeves", "minuet_in_g", "amazing_grace",
                     "chromatic_1234")


def table(names=SINGLE_NOTE_SONGS, envs_=("left", "right"), echo=False, songs=None) -> str:
    """Markdown table of the scripted player's mean per-note scores through the envs (evaluation config): one env
    per entry of `envs_` ("left", "right", "duet") over all songs at once (vmapped). `songs` (Song objects, named by
    `names`) replaces the embedded songs."""
    timelines = [TL.from_song(s) for s in songs] if songs is not None else [TL.from_song(library.load(n))
                                                                             for n in names]
    rows = ["| song | env | hand | notes | F1 | precision | recall | notes with F1 < 1 |",
            "|---|---|---|---|---|---|---|---|"]
    if echo:
        print("\n".join(rows), flush=True)
    for kind in envs_:
        env = envs.make(kind, timelines, envs.EnvConfig().evaluation().sized(len(timelines)))
        results = ScriptedPlayer(env).play(np.arange(len(names)))
        hands = ("left", "right", "both") if kind == "duet" else (kind,)
        for name, res in zip(names, results):
            for hand in hands:
                r = res[hand]
                bad = np.flatnonzero(r["per_note"][:, 2] < 1).tolist()
                rows.append(f"| {name} | {kind} | {hand} | {res['closed']} | {r['f1']:.3f} | {r['precision']:.3f} | "
                            f"{r['recall']:.3f} | {bad if bad else '-'} |")
                if echo:
                    print(rows[-1], flush=True)
            if res["terminated_at"] is not None:
                print(f"warning: {name} ({kind}) terminated at step {res['terminated_at']}", flush=True)
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser(description="F1 of the scripted player on the embedded single-note songs")
    ap.add_argument("--envs", default="left,right", help="comma-separated: left, right, duet")
    ap.add_argument("--songs", default=",".join(SINGLE_NOTE_SONGS), help="embedded song names")
    ap.add_argument("--tabs", nargs="+", help="tab files or folders instead of --songs")
    args = ap.parse_args()
    t0 = time.time()
    if args.tabs:
        songs = library.load_songs(args.tabs)
        names = [s.title for s in songs]
        table(names, tuple(args.envs.split(",")), echo=True, songs=songs)
    else:
        table(args.songs.split(","), tuple(args.envs.split(",")), echo=True)
    print(f"\n({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
