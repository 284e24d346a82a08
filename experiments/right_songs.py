"""The right hand on given songs' picking, as written (no tempo change), warm-started from the general right hand
(`dexguitar songs` starts it from models/policies/right_mixed): the sizes of right_gpu.py. The critic starts fresh, so
for its first 50 iterations only it (and the discriminator) learns: without that warm-up, PPO on a random critic's
advantages took `right_mixed` from F1 0.73-0.86 on turkish_march's windows to 0.05 within 25 iterations."""
from dexguitar.envs import EnvConfig
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="right", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25,
                     actor_warmup=50)
ENV = EnvConfig(shift_prob=0.0, tempo_prob=0.0)
