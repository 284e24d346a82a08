"""What the planner pair plans for chosen notes of a song in the duet (issue 10: why a note is lost for both hands):
per note, the step at which the tracked left plan first holds it, the right plan's stroke (its first crossing and
length), and the frets the env detects under the tracked left plan at each step from one before the note to three
into the next. Note numbers are those of `dexguitar play`'s report (`<out>-report.json`, `experiments/duet_gap.py`).

    python experiments/duet_timing.py ../shared/data/official/notes/snow.json 50 64
"""
import argparse

import numpy as np

from dexguitar.cli import load_song
from dexguitar.envs import EnvConfig, as_batch
from dexguitar.motion import feedforward as FF
from dexguitar.motion.planner import LATEST, ScriptedLeft, ScriptedRight
from dexguitar.music import timeline as TL


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("song")
    p.add_argument("notes", nargs="+", type=int)
    args = p.parse_args()
    songs = as_batch([TL.from_song(load_song(args.song))])
    rest = EnvConfig().count_in                        # row 0: the count-in before the first note
    notes = FF.song_notes(songs, 0, rest)
    keys, found = FF.plan_songs(songs, rest, version=LATEST)
    timing = ScriptedLeft().timing(notes, found[keys[0]][1])
    strokes = {s.note: s for s in ScriptedRight().sweeps(notes, timing)[0]}
    for r in args.notes:
        i = r + 1
        a, b = int(notes.onset[i]), int(notes.onset[i + 1])
        s = strokes.get(i)
        stroke = f"first crossing at step {s.cross - a:.2f}, {s.frames:.1f} frames, {s.strings} strings" if s else "none"
        print(f"note {r}: left goal {notes.left[i].tolist()}, {b - a} frames; left holds it from step "
              f"{int(timing.ready[i]) - a}; stroke: {stroke}")
        for step in range(a - 1, min(b + 3, len(timing.press))):
            print(f"   step {step - a:3d}: {np.asarray(timing.press[step]).tolist()}")


if __name__ == "__main__":
    main()
