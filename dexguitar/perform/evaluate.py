"""Evaluation by the paper's rules: play whole songs with the mean action, collect per-note precision/recall/F1 for
each hand (and both), and aggregate per song and per chord (for a Fig. 5 histogram)."""
from __future__ import annotations

from collections import defaultdict

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs as E
from dexguitar.music import timeline as TL

HANDS = {"left": ("left",), "right": ("right",), "duet": ("left", "right", "both")}


def rollout_song(env, act, song_index: int, frames: int, key=None):
    """Play song `song_index` of the env's batch from its start; `act(obs) -> action`. Returns per-step info
    arrays (frames, ...) and the `done` mask."""
    key = jax.random.PRNGKey(0) if key is None else key
    state = env.reset(key, song_index)

    def one(state, _):
        nxt = env.step(state, act(state.obs))
        alive = ~state.done
        info = jax.tree.map(lambda x: jnp.where(alive, x, jnp.zeros_like(x)), nxt.info)
        info["links"] = nxt.links
        info["qpos"] = nxt.data.qpos
        return jax.tree.map(lambda a, b: jnp.where(state.done, a, b), state, nxt), (info, alive)
    _, (info, alive) = jax.lax.scan(one, state, None, length=frames)
    return info, alive


def note_scores(info, song, hands) -> list[dict]:
    """One row per finished note: index, the note's strings, and [precision, recall, f1] per hand."""
    ends = np.asarray(info["note_end"])
    rows = []
    for t in np.flatnonzero(ends):
        i = int(np.asarray(info["song_note"])[t])           # -1: the grace rest before the song
        if i < 0 and all(np.asarray(info[h])[t, 4] == 0 for h in hands):
            continue                                           # a clean grace rest says nothing
        note = song.notes[i] if 0 <= i < len(song.notes) else None
        row = {"note": i, "frame": int(t), "frets": list(note.frets) if note else None,
               "chord": bool(note and note.is_chord), "rest": bool(note and note.is_rest)}
        for h in hands:
            p, r, f1, tp, predicted, targets = np.asarray(info[h])[t, :6]
            row[h] = {"precision": float(p), "recall": float(r), "f1": float(f1), "tp": int(tp),
                      "predicted": int(predicted), "targets": int(targets)}
        rows.append(row)
    return rows


def summarize(rows, hands) -> dict:
    """Mean precision/recall/F1 per hand over the notes that concern it (a target to press or pick, or a press or
    pick that happened: an open-string note played cleanly is no evidence for the left hand), and per chord."""
    out = {}
    played = [r for r in rows if not r["rest"]]
    for h in hands:
        mine = [r for r in rows if r[h]["targets"] + r[h]["predicted"] > 0]
        vals = np.array([[r[h]["precision"], r[h]["recall"], r[h]["f1"]] for r in mine]) if mine else np.zeros(
            (0, 3))
        out[h] = {"precision": float(vals[:, 0].mean()) if len(vals) else float("nan"),
                  "recall": float(vals[:, 1].mean()) if len(vals) else float("nan"),
                  "f1": float(vals[:, 2].mean()) if len(vals) else float("nan"), "notes": len(vals)}
    chords = defaultdict(list)
    for r in played:
        if r["chord"]:
            chords[tuple(r["frets"])].append(r[hands[0]]["f1"])
    out["chords"] = {" ".join("x" if f < 0 else str(f) for f in reversed(k)): float(np.mean(v))
                     for k, v in chords.items()}
    return out


def evaluate(hand: str, act, songs, env_config=None) -> dict:
    """F1 of a policy `act(obs) -> action` on each song, all songs played at once (one env each, vmapped).
    Returns {title: {"summary", "notes"}}."""
    timelines = [TL.from_song(s) for s in songs]
    cfg = (env_config or E.EnvConfig()).evaluation()
    env = E.make(hand, timelines, cfg)
    frames = max(int(tl.n_frames) for tl in timelines) + 2
    play = jax.jit(jax.vmap(lambda i: rollout_song(env, act, i, frames)))
    info, _ = jax.device_get(play(jnp.arange(len(songs))))
    results = {}
    for i, song in enumerate(songs):
        rows = note_scores(jax.tree.map(lambda x: x[i], info), song, HANDS[hand])
        title = song.title or f"song{i}"
        results[title if title not in results else f"{title} ({i})"] = {"summary": summarize(rows, HANDS[hand]),
                                                                        "notes": rows}
    return results
