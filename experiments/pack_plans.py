"""The planner's plans that a device call needs, made here (or taken from the disk cache) and written compressed into
.cache/plans, which the call carries: a fresh GPU machine then skips planning (256 songs: 6 minutes on its 16 cores).

    python experiments/pack_plans.py --train 128 --eval     # then carry [".data", ".cache/plans"]

--train N: the first N songs of the general material (seed 0) as training windows plan them (5-frame rest);
--eval: the 48 held-out songs (seed 2) and the official ones (.data/official) as evaluation plays them (count-in).
"""
import argparse
import glob
import shutil
from pathlib import Path

import numpy as np

from dexguitar import envs
from dexguitar.motion import feedforward as FF
from dexguitar.music import library, procedural

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--train", type=int, default=0)
    ap.add_argument("--eval", action="store_true")
    ap.add_argument("--official", default=".data/official")
    ap.add_argument("--out", default=".cache/plans")
    a = ap.parse_args()
    train, ev = envs.EnvConfig(feedforward=FF.LATEST), envs.EnvConfig(feedforward=FF.LATEST).evaluation()
    sets = [(procedural.material("left", "general", 0, a.train), train)] if a.train else []
    if a.eval:
        sets += [(procedural.material("left", "general", 2, 48), ev),
                 (library.load_songs(sorted(glob.glob(f"{a.official}/*.json"))), ev)]
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    for songs, config in sets:
        keys, found = FF.plan_songs(envs.as_batch(songs), config.rest_frames, version=int(config.feedforward))
        for k in set(filter(None, keys)):
            np.savez_compressed(out / f"{k}.npz", action=found[k][0], qpos=found[k][1])
    files = list(out.iterdir())
    print(f"{len(files)} plans in {out}, {sum(f.stat().st_size for f in files) / 2**20:.1f} MiB")
