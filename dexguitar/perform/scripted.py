"""The scripted player's F1 table: the IK planner (`dexguitar.motion.planner`, no learning) plays songs through the
envs, scored by the envs themselves: the embedded single-note songs (`experiments/scripted_f1.md`) or any tabs, e.g.
the authors' songs (`experiments/results/scripted_official.md`).

Run `python -m dexguitar.perform.scripted [--envs left,right,duet] [--songs a,b | --tabs FILE_OR_FOLDER ...]`.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from dexguitar import envs
from dexguitar.motion.planner import ScriptedPlayer
from dexguitar.music import library
from dexguitar.music import timeline as TL

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
        env = envs.make(kind, timelines, envs.EnvConfig().evaluation())
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
