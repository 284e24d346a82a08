"""The right hand on one GPU on procedural picking patterns (see left_gpu for the scaling;
`make train-right`)."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="right", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=1_000_000, iterations_per_call=25)
