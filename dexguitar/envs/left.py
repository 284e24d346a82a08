"""Left hand alone: press the frets of each note (paper Sec. 5.1). Six reward columns, one per string (Eq. 3-8)."""
import jax.numpy as jnp

from dexguitar.envs.core import GuitarEnv, Task
from dexguitar.world.guitar import N_STRINGS


class LeftEnv(GuitarEnv):
    roles = ("left",)
    scene = "left"
    reward_columns = tuple(f"string{i}" for i in range(1, N_STRINGS + 1))
    reward_weights = (0.15,) * N_STRINGS                  # reference §8: 0.15 per string objective

    def task(self, state, body, goal_left, targets):
        columns, _, press, tips, failed = self.left_part(state, body, goal_left)
        none = jnp.zeros(N_STRINGS, bool)
        return Task(reward=columns, press=press, tips=tips[None], terminate=failed, picks=none, wrong=none,
                    picking=state.picking)
