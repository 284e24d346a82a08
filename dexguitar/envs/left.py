"""Left hand alone: press the frets of each note (paper Sec. 5.1). Six reward columns, one per string (Eq. 3-8)."""
from dexguitar.envs.core import GuitarEnv


class LeftEnv(GuitarEnv):
    roles = ("left",)
    scene = "left"
    reward_columns = tuple(f"string{i}" for i in range(1, 7))
    goal_size = 35

    def goal(self, state):
        return self.left_goal(state.window, state.note, state.note_frame)

    def task(self, state, data, links, goal_left, targets):
        out = self.left_part(state, data, links, goal_left)
        return dict(out, tips=out["tips"][None])
