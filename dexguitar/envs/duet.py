"""Both hands: the centralized env of synchronization (paper Sec. 5.3). Columns: the left hand's six strings and
the right hand's picking. Cooperative condition: a target string is ready to pick only when the left hand holds every
string in its expected state (the paper's strict gate; `EnvConfig.ready_after = k` relaxes it after k frames of the
note, as the authors' code does with k = 5). Until then the right hand sees no target (the r- case of Eq. 10), and a
pick of a string that is not ready counts as wrong."""
import jax.numpy as jnp

from dexguitar.envs.core import N_STRINGS, GuitarEnv


class DuetEnv(GuitarEnv):
    roles = ("left", "right")
    scene = "duet"
    reward_columns = tuple(f"string{i}" for i in range(1, 7)) + ("pick",)
    goal_size = 70

    def goal(self, state):
        return jnp.concatenate([self.left_goal(state.window, state.note, state.note_frame),
                                self.right_goal(state.window, state.note, state.note_frame, state.picked)])

    def task(self, state, data, links, goal_left, targets):
        left = self.left_part(state, data, links, goal_left)
        ready = left["correct"] > 0
        if self.config.ready_after >= 0:
            ready = ready | (state.note_frame >= self.config.ready_after)
        right = self.right_part(state, data, links, targets, jnp.broadcast_to(ready, (N_STRINGS,)))
        return dict(right, press=left["press"], reward=jnp.concatenate([left["reward"], right["reward"][None]]),
                    tips=jnp.stack([left["tips"], right["tips"]]), terminate=left["terminate"] | right["terminate"])
