"""The tiny left-hand trainer that several tests share (4 envs, one song), built here so that a test's subprocess
(tests/devices_check.py) builds the same one: one compiled program for all."""
from dexguitar.learn.trainer import Trainer, TrainConfig
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import library
from dexguitar.music import timeline as TL


def left_trainer() -> Trainer:
    cfg = TrainConfig(num_envs=4, horizon=4, minibatch=8, epochs=2, disc_steps=2, disc_buffer=64, disc_batch=16,
                      iterations_per_call=1)
    return Trainer(cfg, [TL.from_song(library.load("ode_to_joy"))], reference_frames(load_motion("left")))
