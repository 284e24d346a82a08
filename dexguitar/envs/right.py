"""Right hand alone: pick the target strings of each note once, in a consistent order (paper Sec. 5.2).
One reward column (Eq. 10-16); the critic also sees which strings were tackled wrongly in the note (`privileged`)."""
import jax.numpy as jnp

from dexguitar.envs.core import N_STRINGS, GuitarEnv


class RightEnv(GuitarEnv):
    roles = ("right",)
    scene = "right"
    reward_columns = ("pick",)
    goal_size = 35

    def goal(self, state):
        return self.right_goal(state.window, state.note, state.note_frame, state.picked)

    def task(self, state, data, links, goal_left, targets):
        out = self.right_part(state, data, links, targets, jnp.ones(N_STRINGS, bool))
        out["reward"], out["tips"] = out["reward"][None], out["tips"][None]
        out["press"] = jnp.zeros(N_STRINGS, jnp.int32)
        return out
