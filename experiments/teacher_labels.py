"""What a student of the planner is asked to imitate: how fast the planned actions move, and how candidate labels play.

Prints, over the plans of the first `--songs` songs of the general material (planned as `train --procedural 256`
plans them), each joint's rms step-to-step change of the planned action and its rms distance to the next planned
pose; then the per-note F1 and terminations of the env's hand driven closed-loop by each label on training windows
(`--envs` envs x `--steps` steps):

  open      the plan's action of the song frame
  gain1     the teacher's label (`EnvConfig.teacher`, gain 1)
  pose      the next planned pose as the PD target
  damped    the same plus C_WRIST / C_FINGER seconds x (planned velocity - velocity)
  lagged    damped plus the damping's lag, kd/kp x the planned velocity

    python experiments/teacher_labels.py --songs 32 --envs 16 --steps 600      # docs/results.md, "The learned hands"
"""
from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

C_WRIST, C_FINGER = 0.1, 0.01           # s: velocity feedback through the target (`damped`; 0.2 or 0.15 s on
                                        # the wrist made it unstable)
KD_OVER_KP = (0.4 / 10.0, 0.2 / 10.0)   # wrist, fingers (world/hands.py)
LABELS = ("open", "gain1", "pose", "damped", "lagged")


def label_fn(env, name: str):
    from dexguitar.music import cursor as CU
    plan, j = env.songs.plan, jnp.asarray(env.hands[0].qpos)
    half, home = env._ctrl_half, env._home[j]
    wrist = jnp.arange(27) < 6
    c = jnp.where(wrist, C_WRIST, C_FINGER)
    lag = jnp.where(wrist, *KD_OVER_KP)

    def label(s):
        song = s.cursor.window.song
        f = jnp.clip(CU.song_frame(s.cursor), 0, plan.frames[song] - 1)
        nxt = jnp.clip(f + 1, 0, plan.frames[song] - 1)
        v = s.body.data.qvel[j]
        if name == "open":
            return plan.action[song, f]
        if name == "gain1":
            return env.teacher(s)
        out = (plan.qpos[song, nxt] - home) / half
        if name in ("damped", "lagged"):
            out = out + c * (plan.qvel[song, nxt] - v) / half
        if name == "lagged":
            out = out + lag * plan.qvel[song, nxt] / half
        return jnp.clip(out, -1.0, 1.0)
    return label


def play(env, label, envs: int, steps: int):
    """(per-note F1, notes, terminations) of `label` driving the hand on training windows."""
    def run(key):
        s = jax.vmap(env.reset)(jax.random.split(key, envs))

        def one(s, _):
            s = jax.vmap(env.step)(s, jax.vmap(label)(s))
            sc = s.info["left"]
            counted = (s.info["note_end"] & (sc[:, 4] + sc[:, 5] > 0)).astype(jnp.float32)
            return s, (jnp.sum(sc[:, 2] * counted), jnp.sum(counted), jnp.sum(s.terminated))
        _, (f1, n, t) = jax.lax.scan(one, s, None, length=steps)
        return f1.sum() / n.sum(), n.sum(), t.sum()
    return [float(x) for x in jax.jit(run)(jax.random.PRNGKey(0))]


def main():
    from dexguitar import envs as E
    from dexguitar.music import procedural
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--songs", type=int, default=32)
    ap.add_argument("--envs", type=int, default=16)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--labels", nargs="+", choices=LABELS, default=list(LABELS))
    args = ap.parse_args()
    songs = procedural.material("left", "general", 0, 256)[:args.songs]
    cfg = E.EnvConfig(shift_prob=0.0, tempo_prob=0.0, teacher=True, physics="jax")
    env = E.make("left", songs, cfg)
    base = env.base
    plan = base.songs.plan
    lo, hi = base.model.actuator_ctrlrange.T
    half, home = (hi - lo) / 2, base.model.key_qpos[0]
    step, pose = [], []
    for i in range(args.songs):
        n = int(plan.frames[i])
        a, q = np.asarray(plan.action[i, :n]), np.asarray(plan.qpos[i, :n])
        step.append(np.diff(a, axis=0))
        pose.append(a[:-1] - (q[1:] - home) / half)
    np.set_printoptions(precision=3, suppress=True, linewidth=160)
    print("rms step-to-step change of the planned action, per joint:", np.sqrt((np.concatenate(step) ** 2).mean(0)))
    print("rms planned action - next planned pose, per joint:      ", np.sqrt((np.concatenate(pose) ** 2).mean(0)))
    for name in args.labels:
        t0 = time.time()
        f1, notes, terminations = play(env, label_fn(base, name), args.envs, args.steps)
        print(f"{name:7s} F1 {f1:.3f} over {notes:.0f} notes, {terminations:.0f} terminations ({time.time() - t0:.0f} s)",
              flush=True)


if __name__ == "__main__":
    main()
