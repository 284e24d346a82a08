"""The left hand on given songs as written, warm-started from another left policy (`dexguitar songs` starts it from
models/policies/left_official15, the one left hand of the 15 official songs): the recipe of left_songs (PPO clip
0.3) with a 25-iteration critic warm-up, since the critic starts fresh (right_songs: PPO on a random critic's
advantages undoes a warm-started actor). On super_mario this reached song F1 0.971 in 4.2 minutes under JAX's
physics on one H100, against 0.419 after 3 minutes from scratch, and 0.981-0.990 (four runs) in 167-181 s under
Warp on one H200, compilation included (docs/results.md, "The learned hands"). One GPU."""
import dataclasses

from dexguitar.configs import left_songs as _base

CONFIG = dataclasses.replace(_base.CONFIG, actor_warmup=25)
ENV = _base.ENV
