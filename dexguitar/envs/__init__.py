"""Pure-functional MJX envs: `env.reset(key) -> State`, `env.step(State, action) -> State` (jit + vmap)."""
import dataclasses

from dexguitar.envs.core import Body, EnvConfig, GuitarEnv, Picking, State, Task
from dexguitar.envs.duet import DuetEnv
from dexguitar.envs.layout import ObsLayout
from dexguitar.envs.left import LeftEnv
from dexguitar.envs.right import RightEnv
from dexguitar.envs.wrappers import AutoReset, ChainWindows, PlayThrough, Wrapper
from dexguitar import planner
from dexguitar.music.timeline import as_batch
from dexguitar.world.physics import PHYSICS

ENVS = {"left": LeftEnv, "right": RightEnv, "duet": DuetEnv}


def make(hand: str, songs, config: EnvConfig | None = None, **overrides):
    """The env for `hand` ("left", "right" or "duet") over a song batch (a `Timeline` or a list of them or of
    `Song`s), with its episode logic: training windows chained and auto-reset, or (`config.sequential`) whole songs
    played through. The planner's plans that the config's feedforwards or teacher ask for are made (or read from
    their cache) here, unless the songs carry them already."""
    if hand not in ENVS:
        raise ValueError(f"unknown hand {hand!r}; expected one of {', '.join(ENVS)}")
    config = dataclasses.replace(config or EnvConfig(episode_frames=1200 if hand == "duet" else 600), **overrides)
    if config.feedforward and "left" not in ENVS[hand].roles:
        raise ValueError(f"EnvConfig.feedforward is the left hand's planned motion; the {hand} env has no left hand")
    if config.right_feedforward and "right" not in ENVS[hand].roles:
        raise ValueError(f"EnvConfig.right_feedforward is the right hand's planned motion; the {hand} env has no "
                         "right hand")
    if config.teacher and len(ENVS[hand].roles) != 1:
        raise ValueError(f"EnvConfig.teacher labels one hand from its planner: the left or the right env, not {hand}")
    songs = planner.prepare(songs, config, hand)
    env = ENVS[hand](songs, config)
    if config.plan_wrist_reward and "left" not in env.plans:
        raise ValueError("EnvConfig.plan_wrist_reward rewards the left hand for the planner's hand position: it needs "
                         "the left plans, as a teacher's (the left env) or a feedforward's")
    return PlayThrough(env) if config.sequential else AutoReset(ChainWindows(env))


__all__ = ["PHYSICS", "as_batch", "EnvConfig", "GuitarEnv", "State", "Body", "Picking", "Task", "ObsLayout", "LeftEnv",
           "RightEnv", "DuetEnv", "ENVS", "make", "Wrapper", "ChainWindows", "AutoReset", "PlayThrough"]

