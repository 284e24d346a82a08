"""Table S1 of the paper: 512 envs x 8 steps, minibatch 256, 5 epochs, lr 5e-6 / 1e-4 / 1e-5 (one V100): the
`TrainConfig` defaults, as the authors trained one hand; left_gpu and right_gpu scale it to a current GPU."""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig()
