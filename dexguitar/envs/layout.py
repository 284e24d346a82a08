"""The observation layout: what the numbers of an actor observation are, and which of them belong to which hand.

An observation is `history` frames of every hand's link features, hand after hand within a frame, then every hand's
goal, hand after hand: [frame 0: hand 0 | hand 1 ...] [frame 1: ...] [goal hand 0 | goal hand 1 ...]. A hand's own
slice of a two-hand observation is exactly the observation its one-hand env would give, which is what lets frozen
single-hand policies play in the duet. The env builds its layout from the shapes it produces (`jax.eval_shape`), so
no size is written twice.
"""
from __future__ import annotations

import dataclasses

import jax.numpy as jnp


@dataclasses.dataclass(frozen=True)
class ObsLayout:
    roles: tuple[str, ...]     # hands, in observation order
    history: int               # frames of link features
    frame: int                 # numbers per hand per frame
    goal: int                  # goal numbers per hand
    privileged: int            # numbers only the critic sees (after the goal)

    @property
    def hands(self) -> int:
        return len(self.roles)

    @property
    def frame_size(self) -> int:
        return self.frame * self.hands

    @property
    def goal_size(self) -> int:
        return self.goal * self.hands

    @property
    def obs_size(self) -> int:
        return self.history * self.frame_size + self.goal_size

    def split(self, obs):
        """(..., obs_size) -> (frames (..., history, frame_size), goal (..., goal_size))."""
        state, goal = obs[..., :-self.goal_size], obs[..., -self.goal_size:]
        return state.reshape(state.shape[:-1] + (self.history, self.frame_size)), goal

    def hand_parts(self, frames, goal, i: int):
        """Hand i's frames (..., history, frame) and goal (..., goal) out of a split observation."""
        return (frames[..., i * self.frame:(i + 1) * self.frame], goal[..., i * self.goal:(i + 1) * self.goal])

    def hand_obs(self, obs, i: int):
        """Hand i's observation (..., one-hand obs_size), as its one-hand env builds it."""
        frames, goal = self.hand_parts(*self.split(obs), i)
        return jnp.concatenate([frames.reshape(frames.shape[:-2] + (-1,)), goal], axis=-1)

    def one_hand(self, i: int) -> "ObsLayout":
        return dataclasses.replace(self, roles=(self.roles[i],))

    def to_dict(self) -> dict:
        return dataclasses.asdict(self) | {"roles": list(self.roles)}

    @classmethod
    def from_dict(cls, d: dict) -> "ObsLayout":
        return cls(**{**d, "roles": tuple(d["roles"])})
