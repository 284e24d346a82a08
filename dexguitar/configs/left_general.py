"""The general-purpose left hand by PPO alone (paper Sec. 6.1-6.2): the sizes and learning rates of left_gpu on the
balanced procedural material (`dexguitar train --hand left --style general`: 2000 songs of chords, lines and jumps
across the neck), with the paper's fret-shift and tempo augmentation (EnvConfig defaults). The paper trains it for
about 8e8 samples: 24,400 iterations of 32,768. After 2.07e8 samples (one H100) it played the 15 official songs
zero-shot at a mean left F1 of 0.188 (docs/results.md, "The learned hands").

    dexguitar train --hand left --style general --config left_general --out runs/left-general-ppo
"""
from dexguitar.learn.trainer import TrainConfig

CONFIG = TrainConfig(hand="left", num_envs=4096, horizon=8, minibatch=4096, epochs=5, actor_lr=1e-4,
                     critic_lr=3e-4, disc_lr=1e-4, disc_steps=8, iterations=24_400, iterations_per_call=25)
