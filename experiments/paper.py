"""Table S1 of the paper: 512 envs x 8 steps, minibatch 256, 5 epochs, lr 5e-6 / 1e-4 / 1e-5 (one V100)."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig()
