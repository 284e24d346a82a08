"""Both hands: the centralized env of synchronization (paper Sec. 5.3). Columns: the left hand's six strings and
the right hand's picking. Cooperative condition: a target string is ready to pick only when the left hand holds every
string in its expected state (the paper's strict gate; `EnvConfig.ready_after = k` relaxes it after k frames of the
note, as the authors' code does with k = 5). Until then the right hand's reward sees no target (the r- case of
Eq. 10), and a pick of a string that is not ready is wrong for the reward. The scores judge each hand by the paper's
rules: a pick before the press is no picking error of the right hand, but it fails both-hands F1."""
import jax.numpy as jnp

from dexguitar.envs.core import GuitarEnv, Task
from dexguitar.world.guitar import N_STRINGS


class DuetEnv(GuitarEnv):
    roles = ("left", "right")
    scene = "duet"
    reward_columns = tuple(f"string{i}" for i in range(1, N_STRINGS + 1)) + ("pick",)
    # Reference §5.3: the authors' two-hand weights [0.075 x 6, 0.5] doubled, so that with the discriminators'
    # 0.025 x 2 (also doubled) they sum to 2.
    reward_weights = (0.15,) * N_STRINGS + (1.0,)

    def task(self, state, body, goal_left, targets):
        columns, correct, press, tips_l, failed_l = self.left_part(state, body, goal_left)
        ready = correct > 0
        if self.config.ready_after >= 0:
            ready = ready | (state.cursor.note_frame >= self.config.ready_after)
        reward, picks, wrong, picking, tips_r, failed_r = self.right_part(state, body, targets,
                                                                          jnp.broadcast_to(ready, (N_STRINGS,)))
        return Task(reward=jnp.concatenate([columns, reward[None]]), press=press,
                    tips=jnp.stack([tips_l, tips_r]), terminate=failed_l | failed_r, picks=picks, wrong=wrong,
                    picking=picking)
