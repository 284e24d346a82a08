"""The right hand on given songs' picking, as written (no tempo change), warm-started from the general right hand
(`dexguitar songs` starts it from models/policies/right_mixed): the sizes of right_gpu (one GPU). The critic starts
fresh, so for its first 50 iterations only it (and the discriminator) learns: without that warm-up, PPO on a random
critic's advantages took `right_mixed` from F1 0.73-0.86 on turkish_march's windows to 0.05 within 25 iterations."""
import dataclasses

from dexguitar.configs import right_gpu as _base
from dexguitar.envs import EnvConfig

CONFIG = dataclasses.replace(_base.CONFIG, actor_warmup=50)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
