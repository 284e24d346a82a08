"""Pure-functional MJX envs: `env.reset(key) -> State`, `env.step(State, action) -> State` (jit + vmap)."""
from dexguitar.envs.core import EnvConfig, GuitarEnv, State, Window
from dexguitar.envs.duet import DuetEnv
from dexguitar.envs.left import LeftEnv
from dexguitar.envs.right import RightEnv

ENVS = {"left": LeftEnv, "right": RightEnv, "duet": DuetEnv}


def make(hand: str, songs, config: EnvConfig | None = None, **overrides) -> GuitarEnv:
    """The env for `hand` ("left", "right" or "duet") over a song batch (a `Timeline` or a list of them)."""
    import dataclasses

    from dexguitar.music import timeline as TL
    if hand not in ENVS:
        raise ValueError(f"unknown hand {hand!r}; expected one of {', '.join(ENVS)}")
    if isinstance(songs, (list, tuple)):
        songs = TL.stack([s if isinstance(s, TL.Timeline) else TL.from_song(s) for s in songs])
    config = config or EnvConfig(episode_frames=1200 if hand == "duet" else 600)
    return ENVS[hand](songs, dataclasses.replace(config, **overrides))


__all__ = ["EnvConfig", "GuitarEnv", "State", "Window", "LeftEnv", "RightEnv", "DuetEnv", "ENVS", "make"]
