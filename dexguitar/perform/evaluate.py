"""Evaluation by the paper's rules: play whole songs with the mean action, collect per-note precision/recall/F1 for
each hand (and both), and aggregate per song and per chord (for a Fig. 5 histogram).

The songs are played at once, one env each, until every one is over (a `while_loop`, so no song length is compiled
in). The policy's parameters and the songs are arguments of one cached, jitted program per (hand, env config, policy
spec): evaluating another song set of the same capacities, the same policy after more training, or a synchronizer
before and after (`policy.unsynchronized`) reuses it.
"""
from __future__ import annotations

import json
import math
import time
from collections import defaultdict

import jax
import jax.numpy as jnp
import numpy as np

from dexguitar import envs as E
from dexguitar.world.scoring import per_note_both
from dexguitar.learn.policy import PolicySpec, act_fn, unsynchronized
from dexguitar.learn.tracing import fresh_trace
from dexguitar import planner
from dexguitar.music import timeline as TL
from dexguitar.world import hands as H
from dexguitar.world import physics as P

HANDS = {"left": ("left",), "right": ("right",), "duet": ("left", "right", "both")}
# Songs a CPU plays at once in the duet. Five or six in one program stalled XLA's CPU run on a 2-core machine every
# time it was tried (the process idle in `device_get`); four or fewer never did. One hand stalled the same way with
# 48 songs (`--procedural 48`, twice), never with 16 or 32.
CPU_DUET_SONGS = 4
CPU_HAND_SONGS = 16
RECORD_ROUND = 1024         # `evaluate(record=True)` records a multiple of this many steps (one program per multiple)


def rollout_notes(env, act, params, song_index, key, hands, record: int = 0, joints=()):
    """Play songs `song_index` (n,) of the env's batch from their start, one env each (keys `key` (n,)), with
    `act(params, obs)` until every one is over. Returns (scores (n, W, hands, 6): [precision, recall, f1, tp,
    predicted, targets] of each window row, ended (n, W): the row was played to its end). With `record` > 0, also
    (qpos (n, record, len(joints)): the joint values `joints` (qpos addresses) after each of the first `record`
    steps, steps (n,): the steps each song was played), for the motion line (`motion_quality`).

    The loop is outside the vmap, not a vmapped loop (which is the same program: a song that is over keeps its
    state): batching a `while_loop` re-batches its body until the carry's batching settles, half of the trace."""
    W = env.window_capacity

    def one(state, scores, ended):
        nxt = env.step(state, act(params, state.obs)[0])
        row, end = state.cursor.note, nxt.info["note_end"]
        # this note's scores ("both" judged within the note: final only for the last note) ...
        value = jnp.stack([nxt.info["both_now" if h == "both" else h] for h in hands])
        scores = scores.at[row].set(jnp.where(end, value, scores[row]))
        if "both" in hands:     # ... and the previous note's final both-hands verdict (scoring.close)
            b, prev = hands.index("both"), jnp.maximum(row - 1, 0)
            scores = scores.at[prev, b].set(jnp.where(end & (row > 0), nxt.info["both"], scores[prev, b]))
        return nxt, scores, ended.at[row].set(ended[row] | end)

    def body(carry):
        playing = ~carry[0].done
        return P.where(playing, jax.vmap(one)(*carry), carry)
    state = jax.vmap(env.reset)(key, song_index)
    n = song_index.shape[0]
    carry = (state, jnp.zeros((n, W, len(hands), 6), jnp.float32), jnp.zeros((n, W), bool))
    if not record:
        _, scores, ended = jax.lax.while_loop(lambda c: jnp.any(~c[0].done), body, carry)
        return scores, ended
    joints = jnp.asarray(joints)

    def recording(c):       # every song plays from step 0 and stays over once over: its steps are a prefix
        playing = ~c[0][0].done
        played = body(c[0])
        i = jnp.minimum(c[3], record - 1)
        q = jnp.where((playing & (c[3] < record))[:, None], played[0].body.data.qpos[:, joints], c[1][:, i])
        return played, c[1].at[:, i].set(q), c[2] + playing, c[3] + 1
    rec = (carry, jnp.zeros((n, record, joints.shape[0]), jnp.float32), jnp.zeros(n, jnp.int32), jnp.int32(0))
    (_, scores, ended), qpos, steps, _ = jax.lax.while_loop(lambda c: jnp.any(~c[0][0].done), recording, rec)
    return scores, ended, qpos, steps


def rollout_song(env, act, song_index: int, frames: int, key=None, xs=None):
    """Play song `song_index` of the env's batch from its start for `frames` steps, recording every step (for
    videos); `act(obs) -> action`, or with per-step inputs `xs` (leading axis `frames`, e.g. noise keys)
    `act(obs, x) -> action`. Returns per-step info arrays (frames, ...) and the `alive` mask."""
    key = jax.random.PRNGKey(0) if key is None else key
    state = env.reset(key, song_index)

    def one(state, x):
        nxt = env.step(state, act(state.obs) if xs is None else act(state.obs, x))
        alive = ~state.done
        info = jax.tree.map(lambda x: jnp.where(alive, x, jnp.zeros_like(x)), nxt.info)
        info["links"] = nxt.body.links
        info["qpos"] = nxt.body.data.qpos
        return P.where(state.done, state, nxt), (info, alive)
    _, (info, alive) = jax.lax.scan(one, state, xs, length=frames)
    return info, alive


def note_scores(info, song, hands) -> list[dict]:
    """One row per finished note of a per-step recording (`rollout_song`): as `note_rows`."""
    ends = np.asarray(info["note_end"])
    info = dict(info)
    if "both" in hands:         # the end of note k+1 holds note k's final both-hands verdict (scoring.close)
        both = np.zeros_like(np.asarray(info["both"]))
        both[ends] = per_note_both(np.asarray(info["both"])[ends], np.asarray(info["both_now"])[ends])
        info["both"] = both
    rows = []
    for t in np.flatnonzero(ends):
        i = int(np.asarray(info["song_note"])[t])           # -1: the grace rest before the song
        if i < 0 and all(np.asarray(info[h])[t, 4] == 0 for h in hands):
            continue
        note = song.notes[i] if 0 <= i < len(song.notes) else None
        row = {"note": i, "frame": int(t), "frets": list(note.frets) if note else None,
               "chord": bool(note and note.is_chord), "rest": bool(note and note.is_rest)}
        for h in hands:
            p, r, f1, tp, predicted, targets = np.asarray(info[h])[t, :6]
            row[h] = {"precision": float(p), "recall": float(r), "f1": float(f1), "tp": int(tp),
                      "predicted": int(predicted), "targets": int(targets)}
        rows.append(row)
    return rows


_CACHE: dict = {}
COMPILE_SECONDS: dict = {}        # how long each cached program took to compile (or to load from the disk cache)


def _compiled(hand, env_config, spec, params, songs, record: int = 0):
    """The compiled play(params, songs) -> (scores, ended, note frames): one per hand, env config, policy spec and
    song batch capacity, kept for the life of the process. `record` > 0 (a program of its own): also the fretting
    hand's 27 joint values of the first `record` steps and each song's steps (`rollout_notes`)."""
    key = (hand, env_config, spec, str(jax.tree.map(lambda x: (x.shape, str(x.dtype)), songs)))
    key = key + (("record", record),) if record else key
    if key not in _CACHE:
        env = E.make(hand, songs, env_config)
        act = act_fn(spec, deterministic=True)
        if record and "left" not in env.roles:
            raise ValueError(f"a {hand} evaluation has no fretting hand to record")
        joints = env.hands[env.roles.index("left")].qpos if record else ()

        def play(params, songs_):
            bound = env.bind(songs_)
            n = songs_.n_notes.shape[0]
            keys = jax.random.split(jax.random.PRNGKey(0), n)
            out = rollout_notes(bound, act, params, jnp.arange(n), keys, HANDS[hand], record, joints)
            # each song's note lengths, as the env played them (in the program: no small programs on the host)
            dur = jax.vmap(lambda i: bound.sample_window(jax.random.PRNGKey(0), i).dur)(jnp.arange(n))
            return out[:2] + (dur,) + out[2:]
        t0 = time.perf_counter()
        fresh_trace()              # the same program whatever the process traced before (`learn.tracing`)
        _CACHE[key] = jax.jit(play).lower(params, songs).compile()
        COMPILE_SECONDS[key] = time.perf_counter() - t0
    return _CACHE[key]


def note_rows(scores, ended, dur, song, hands) -> list[dict]:
    """One row per finished note: its song index (-1: the grace rest), the frame it ended, its strings, and
    [precision, recall, f1] per hand. A clean grace rest says nothing and is left out."""
    ends = np.cumsum(dur) - 1
    rows = []
    for w in np.flatnonzero(ended):
        i = int(w) - 1
        if i < 0 and all(scores[w, k, 4] == 0 for k in range(len(hands))):
            continue
        note = song.notes[i] if 0 <= i < len(song.notes) else None
        row = {"note": i, "frame": int(ends[w]), "frets": list(note.frets) if note else None,
               "chord": bool(note and note.is_chord), "rest": bool(note and note.is_rest)}
        for k, h in enumerate(hands):
            p, r, f1, tp, predicted, targets = (float(x) for x in scores[w, k, :6])
            row[h] = {"precision": p, "recall": r, "f1": f1, "tp": int(tp), "predicted": int(predicted),
                      "targets": int(targets)}
        rows.append(row)
    return rows


UNDEFINED = "no note concerned this hand: nothing to press or pick, and nothing pressed or picked"


def summarize(rows, hands) -> dict:
    """Mean precision/recall/F1 per hand over the notes that concern it (a target to press or pick, or a press or
    pick that happened: an open-string note played cleanly is no evidence for the left hand), and per chord. A hand
    no note concerned has NaN means (null in JSON, `dumps`) and `undefined`, the reason."""
    out = {}
    played = [r for r in rows if not r["rest"]]
    for h in hands:
        mine = [r for r in rows if r[h]["targets"] + r[h]["predicted"] > 0]
        vals = np.array([[r[h]["precision"], r[h]["recall"], r[h]["f1"]] for r in mine]) if mine else np.zeros(
            (0, 3))
        out[h] = {"precision": float(vals[:, 0].mean()) if len(vals) else float("nan"),
                  "recall": float(vals[:, 1].mean()) if len(vals) else float("nan"),
                  "f1": float(vals[:, 2].mean()) if len(vals) else float("nan"), "notes": len(vals)}
        if not len(vals):
            out[h]["undefined"] = UNDEFINED
    chords = defaultdict(list)
    for r in played:
        if r["chord"]:
            chords[tuple(r["frets"])].append(r[hands[0]]["f1"])
    out["chords"] = {" ".join("x" if f < 0 else str(f) for f in reversed(k)): float(np.mean(v))
                     for k, v in chords.items()}
    return out


def finite(obj):
    """`obj` for JSON, which has no NaN or infinity: every such float becomes None (null), NumPy scalars plain
    numbers; dicts, lists and tuples are copied."""
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def dumps(obj, **kwargs) -> str:
    """`json.dumps` of results: undefined numbers (NaN, infinity) written as null (`finite`), never as the `NaN`
    that JSON readers other than Python's refuse."""
    return json.dumps(finite(obj), allow_nan=False, **kwargs)


def evaluate(params: dict, spec: PolicySpec, songs, env_config=None, hand: str | None = None,
             record: bool = False) -> dict:
    """F1 of a policy on each song, all songs played at once (one env each; on a CPU `CPU_DUET_SONGS` or
    `CPU_HAND_SONGS` at a time). `hand` defaults to the policy's (a synchronizer plays the duet). Returns
    {title: {"summary", "notes"}}; `record`: also "qpos", the fretting hand's (frames, 27) joint values at the
    control rate in the left-hand model's order (`motion_quality`)."""
    hand = hand or spec.hand
    cfg = spec.env_config(env_config or E.EnvConfig()).evaluation()
    params = jax.tree.map(jnp.asarray, params)
    size = max(len(songs), 1)
    if jax.default_backend() == "cpu":
        size = min(size, CPU_DUET_SONGS if hand == "duet" else CPU_HAND_SONGS)
    cfg = cfg.sized(size)                  # under Warp, its contact buffer for one env per song of a batch
    timelines = [TL.from_song(s) for s in songs]
    if size < len(songs) and (cfg.feedforward or cfg.right_feedforward):   # plan every song in one pool; the
        every = TL.batch(timelines)                                           # chunks read the plans' disk cache
        if cfg.feedforward:
            planner.plan_songs(every, cfg.rest_frames)
        if cfg.right_feedforward:
            planner.plan_songs(every, cfg.rest_frames, hand="right", after=planner.left_plans(every, cfg))
    results = {}
    for start in range(0, len(songs), size):
        part = songs[start:start + size]
        batch = planner.prepare(TL.batch(timelines[start:start + size]), cfg, hand)
        # a song plays its frames after the count-in; rounded up so song sets of about one length share a program
        frames = max(int(t.n_frames) for t in timelines[start:start + size]) + cfg.rest_frames + 1
        record_steps = -(-frames // RECORD_ROUND) * RECORD_ROUND if record else 0
        play = _compiled(hand, cfg, spec, params, batch, record_steps)
        scores, ended, dur, *recorded = jax.device_get(play(params, batch))
        for j, song in enumerate(part):
            i = start + j
            rows = note_rows(scores[j], ended[j], np.asarray(dur[j]), song, HANDS[hand])
            title = song.title or f"song{i}"
            title = title if title not in results else f"{title} ({i})"
            results[title] = {"summary": summarize(rows, HANDS[hand]), "notes": rows}
            if record:
                steps = int(recorded[1][j])
                if steps > record_steps:
                    raise RuntimeError(f"{title}: played {steps} steps, more than the {record_steps} recorded")
                q = np.asarray(recorded[0][j][:steps])
                results[title]["qpos"] = H.mirror_qpos(q, side_from="right") if cfg.mirror else q
    return results


def evaluate_synchronizer(params: dict, spec: PolicySpec, songs, env_config=None, record: bool = False) -> dict:
    """{"before": results, "after": results}: a synchronizer's two frozen policies alone, then synchronized."""
    return {"before": evaluate(unsynchronized(params), spec, songs, env_config, record=record),
            "after": evaluate(params, spec, songs, env_config, record=record)}
