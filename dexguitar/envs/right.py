"""Right hand alone: pick the target strings of each note once, in a consistent order (paper Sec. 5.2).
One reward column (Eq. 10-16); the critic also sees which strings were tackled wrongly in the note (`privileged`)."""
import jax.numpy as jnp

from dexguitar.envs.core import GuitarEnv, Task
from dexguitar.world.guitar import N_STRINGS


class RightEnv(GuitarEnv):
    roles = ("right",)
    scene = "right"
    reward_columns = ("pick",)
    reward_weights = (0.5,)                               # reference §8: goal 0.5, discriminator 0.5

    def task(self, state, body, goal_left, targets):
        reward, picks, wrong, picking, tips, failed = self.right_part(state, body, targets,
                                                                      jnp.ones(N_STRINGS, bool))
        return Task(reward=reward[None], press=jnp.zeros(N_STRINGS, jnp.int32), tips=tips[None], terminate=failed,
                    picks=picks, wrong=wrong, picking=picking)
