"""How big a run's checkpoints are for a config: the train state in memory per field, and on disk the whole state
(`ckpt/`) against its compact part (`resume/`, what a run carries from machine to machine). The state is a fresh
one (`Trainer.init`): a trained one has the same shapes, but its optimizer moments no longer compress.

    python experiments/checkpoint_size.py --config experiments/left_general.py --style general   # about 20 s on a CPU
"""
import argparse
import subprocess
import tempfile
from pathlib import Path

import jax
import numpy as np

from dexguitar.learn import checkpoint as C
from dexguitar.learn.run import compact, load_config
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import procedural, timeline as TL


def mib(tree) -> float:
    return sum(np.prod(x.shape) * np.dtype(x.dtype).itemsize for x in jax.tree.leaves(tree)) / 2 ** 20


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="experiments/left_general.py")
    ap.add_argument("--hand", default="left")
    ap.add_argument("--style", default="general")
    args = ap.parse_args()
    cfg, env_cfg = load_config(args.config, hand=args.hand)
    songs = procedural.material(args.hand, args.style, 0, None)
    trainer = Trainer(cfg, [TL.from_song(s) for s in songs], reference_frames(load_motion(args.hand)), env_cfg)
    state = trainer.init()
    print(f"{cfg.num_envs} envs; the train state in memory, MiB:")
    for name in ("params", "opt", "obs_norm", "disc_norm", "popart", "buffers", "env"):
        print(f"  {name:10s} {mib(getattr(state, name)):8.1f}")
    print(f"  {'total':10s} {mib(state):8.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        C.save(Path(tmp) / "ckpt", 1, state)
        C.save(Path(tmp) / "resume", 1, state, keep=1, only=compact)
        for d in ("ckpt", "resume"):
            on_disk = sum(f.stat().st_size for f in (Path(tmp) / d).rglob("*") if f.is_file())
            packed = len(subprocess.run(["tar", "czf", "-", "-C", tmp, d], capture_output=True, check=True).stdout)
            print(f"{d + '/':8s} on disk {on_disk / 1e6:6.1f} MB, as a .tgz {packed / 1e6:6.1f} MB")


if __name__ == "__main__":
    main()
