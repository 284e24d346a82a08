"""Synchronization in `dexguitar songs`: sync_gpu with a 50-iteration critic warm-up, for the reason of right_songs:
the synchronizer starts as the identity (its last layer is zero) but its critic starts fresh, and PPO on a random
critic's advantages moves a warm-started actor (one GPU). Measured on one H100 with the per-song pipeline's pairs:
come_as_you_are 0.778 -> 0.953 with it; on wipe_out the pair got worse with it (0.918 -> 0.873) and without it
(0.945 -> 0.918), so the warm-up is not what decides there."""
import dataclasses

from dexguitar.configs import sync_gpu as _base

CONFIG = dataclasses.replace(_base.CONFIG, actor_warmup=50)
