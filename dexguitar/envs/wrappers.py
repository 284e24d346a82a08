"""Episode logic around the pure control step (`GuitarEnv.step`), as small wrappers that `envs.make` composes:

- `ChainWindows` (training): a window that has been played out is followed at once by a fresh random window, without a
  reset, so an episode spans several windows;
- `AutoReset` (training): the time limit, and the reset inside `step`: the state returned for a finished episode is
  the next episode's first state, carrying the finished transition's reward, done, terminated and info;
- `PlayThrough` (evaluation): the episode ends with the song (or a failure) and nothing resets; callers mask what
  follows by `done`.

A wrapper is the env it wraps plus one rule: every other attribute is the wrapped env's.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from dexguitar.music import cursor as CU
from dexguitar.world.physics import where as tree_where


class Wrapper:
    def __init__(self, env):
        self.env = env

    def __getattr__(self, name):
        return getattr(self.env, name)

    def bind(self, songs):
        return type(self)(self.env.bind(songs))

    def reset(self, key, song=None):
        return self.env.reset(key, song)

    def step(self, state, action):
        return self.env.step(state, action)

    @property
    def base(self):
        """The pure env inside every wrapper."""
        return self.env.base if isinstance(self.env, Wrapper) else self.env


class ChainWindows(Wrapper):
    def step(self, state, action):
        s = self.env.step(state, action)
        if self.env.planned:      # a planned song's window ends its episode: the next starts in its planned state
            return s.replace(done=s.done | s.cursor.over)
        key, k_win = jax.random.split(s.key)
        over = s.cursor.over
        cursor = tree_where(over, CU.start(self.env.sample_window(k_win)), s.cursor)
        obs = jnp.where(over, self.env.observe(s.body, cursor, s.picking), s.obs)
        return s.replace(cursor=cursor, obs=obs, key=key)


class AutoReset(Wrapper):
    def step(self, state, action):
        s = self.env.step(state, action)
        done = s.done | (s.lifetime >= self.env.config.episode_frames)
        key, k_reset = jax.random.split(s.key)
        fresh = self.env.reset(k_reset).replace(reward=s.reward, done=done, terminated=s.terminated, info=s.info)
        return tree_where(done, fresh, s.replace(done=done, key=key))


class PlayThrough(Wrapper):
    def step(self, state, action):
        s = self.env.step(state, action)
        return s.replace(done=s.done | s.cursor.over)
