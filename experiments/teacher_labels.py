"""What a student of the planner is asked to imitate: how fast the planned actions move, and how candidate labels play.

Prints, over the plans of the first `--songs` songs of the general material (planned as `train --procedural 256`
plans them), each joint's rms step-to-step change of the planned action and its rms distance to the next planned
pose; then the per-note F1 and terminations of the env's hand driven closed-loop by each label on training windows
(`--envs` envs x `--steps` steps):

  open      the plan's action of the song frame
  gain1     the teacher's label (`EnvConfig.teacher`, gain 1)
  gain4     the same at gain 4
  gain1d    gain1 plus C_WRIST / C_FINGER seconds x (planned velocity - velocity): damping through the target
            (`EnvConfig.teacher_damping`, `teacher_finger_damping`)
  pose      the next planned pose as the PD target
  damped    the same plus C_WRIST / C_FINGER seconds x (planned velocity - velocity)
  lagged    damped plus the damping's lag, kd/kp x the planned velocity

each also with Gaussian noise of `--play-noise` stds on its actions (what a student's error does to it).

    python experiments/teacher_labels.py --songs 32 --envs 16 --steps 600      # docs/results.md, "The learned hands"

With `--hand right`, the same of the right planner's labels on held-out songs of the mixed material (seed 1000):

    python experiments/teacher_labels.py --hand right --songs 16 --steps 400 --labels open --play-noise 0 0.01 0.03 0.1

With `--fit`, what a student can learn of the labels from what it sees: the gain-1 labels of states visited by the
labels plus Gaussian noise (`--noise`, DAgger's spread) are regressed by an MLP (512-256-128; the policy's is
1024-1024-512) from each input set below, fitted on the first three quarters of the songs and measured (label rms, in
half ranges) on the last quarter and closed-loop (per-note F1 of the fitted MLP acting, with no noise):

  obs        the policy's observation (2 frames of link states, 5 upcoming notes)
  joints     obs + the hand's joint positions and velocities
  plan       obs + the plan's pose of the next frame (which a planner-free student must infer from the notes)
  plan-wrist, plan-fingers   obs + the same pose's wrist joints only, or its finger joints only (the fingering)
  all        obs + joints + plan

    python experiments/teacher_labels.py --fit --songs 64 --envs 16 --steps 4000     # docs/results.md

With `--student POLICY`, where a trained student departs from its teacher: the policy's mean action and the teacher
(the damped label of `--c-wrist` / `--c-finger`) each drive the hand on training windows of the first `--songs`
songs it trained on and of as many held-out ones (seed 1000), and so do the two mixes of the student's wrist and the
teacher's fingers and the reverse; per driver, F1 by the note's pressed strings and lowest fret, and for the student
the rms of (its action - the label) on its own states, per joint group, in the first frames of a note (the shift to
it) and after.

    python experiments/teacher_labels.py --student runs/left-learned-damped/policy --songs 16 --c-finger 0.03
"""
from __future__ import annotations

import argparse
import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np

C_WRIST, C_FINGER = 0.1, 0.01           # s: velocity feedback through the target (`damped`; 0.2 or 0.15 s on
                                        # the wrist made it unstable)
KD_OVER_KP = (0.4 / 10.0, 0.2 / 10.0)   # wrist, fingers (world/hands.py)
LABELS = ("open", "gain1", "gain4", "gain1d", "pose", "damped", "lagged")
INPUTS = ("obs", "joints", "plan", "plan-wrist", "plan-fingers", "all")
NOISE_ON = {"all": (True, True), "wrist": (True, False), "fingers": (False, True)}   # (wrist, fingers)


def is_wrist():
    """(27,) bool: the left hand's wrist joints."""
    from dexguitar.world.hands import N_DOF, WRIST_DOF
    return jnp.arange(N_DOF) < WRIST_DOF


def label_fn(env, name: str):
    from dexguitar.music import cursor as CU
    plan, j = env.plans[env.roles[0]], jnp.asarray(env.hands[0].qpos)
    half, home = env._ctrl_half, env._home[j]
    c = jnp.where(is_wrist(), C_WRIST, C_FINGER)
    lag = jnp.where(is_wrist(), *KD_OVER_KP)
    teachers = {"gain1": {}, "gain4": {"teacher_gain": 4.0},
                "gain1d": {"teacher_damping": C_WRIST, "teacher_finger_damping": C_FINGER}}
    if name in teachers:      # the env's own teacher with these fields
        return type(env)(env.songs, dataclasses.replace(env.config, **teachers[name])).teacher

    def label(s):
        song = s.cursor.window.song
        f = jnp.clip(CU.song_frame(s.cursor), 0, plan.frames[song] - 1)
        nxt = jnp.clip(f + 1, 0, plan.frames[song] - 1)
        v = s.body.data.qvel[j]
        if name == "open":
            return plan.action[song, f]
        out = (plan.qpos[song, nxt] - home) / half
        if name in ("damped", "lagged"):
            out = out + c * (plan.qvel[song, nxt] - v) / half
        if name == "lagged":
            out = out + lag * plan.qvel[song, nxt] / half
        return jnp.clip(out, -1.0, 1.0)
    return label


def rollout(env, act, envs: int, steps: int, key, noise=0.0, record=None):
    """Per step and env (steps, envs, ...): `act(state)` plus `noise` x N(0, 1) (a scalar or one per joint) driving
    the env's hand on training windows; the closed notes' F1, whether each counts, terminations, and
    `record(state, action)` of the state acted in. `key`: (the resets' key, the noise's key), or one key split into
    them. Traced inside the caller's jit."""
    hand = env.base.roles[0]
    k0, k1 = key if isinstance(key, tuple) else jax.random.split(key)
    s = jax.vmap(env.reset)(jax.random.split(k0, envs))

    def one(s, k):
        a = jax.vmap(act)(s)
        rec = jax.vmap(record)(s, a) if record else {}
        s = jax.vmap(env.step)(s, a + noise * jax.random.normal(k, a.shape))
        sc = s.info[hand]
        rec.update(f1=sc[:, 2], counted=s.info["note_end"] & (sc[:, 4] + sc[:, 5] > 0), terminated=s.terminated)
        return s, rec
    return jax.lax.scan(one, s, jax.random.split(k1, steps))[1]


def play(env, label, envs: int, steps: int, noises=(0.0,), on: str = "all"):
    """[(per-note F1, notes, terminations)] of `label` plus noise x N(0, 1) on the joints `on` (NOISE_ON) driving the
    env's hand on training windows, for each noise of `noises` (one program for all)."""
    mask = jnp.where(is_wrist(), *NOISE_ON[on]).astype(jnp.float32)

    @jax.jit
    def run(key, noise):
        rec = rollout(env, label, envs, steps, key, noise * mask)
        counted = rec["counted"].astype(jnp.float32)
        return jnp.sum(rec["f1"] * counted) / counted.sum(), counted.sum(), rec["terminated"].sum()
    return [[float(x) for x in run(jax.random.PRNGKey(0), jnp.float32(noise))] for noise in noises]


def seen(base, s):
    """What a student may see of state `s`: the observation, the joints (velocities x 0.1 s) and the next planned
    pose."""
    from dexguitar.music import cursor as CU
    plan, j, song = base.songs.plan, jnp.asarray(base.hands[0].qpos), s.cursor.window.song
    nxt = jnp.clip(CU.song_frame(s.cursor) + 1, 0, plan.frames[song] - 1)
    d = s.body.data
    pose = plan.qpos[song, nxt]
    return {"obs": s.obs, "joints": jnp.concatenate([d.qpos[j], 0.1 * d.qvel[j]]), "plan": pose,
            "plan-wrist": jnp.where(is_wrist(), pose, 0.0), "plan-fingers": jnp.where(is_wrist(), 0.0, pose)}


def collect(env, envs: int, steps: int, noise: float, key):
    """{obs, joints, plan, label, song} per visited state (steps x envs rows), the hand driven by the gain-1 label
    plus `noise` x N(0, 1)."""
    base = env.base

    def features(s, _):
        return dict(seen(base, s), label=base.teacher(s), song=s.cursor.window.song)
    out = jax.jit(lambda key: rollout(env, base.teacher, envs, steps, key, noise, features))(key)
    return {k: np.asarray(out[k]).reshape(envs * steps, -1) for k in ("obs", "joints", "plan", "plan-wrist",
                                                                       "plan-fingers", "label", "song")}


def inputs(rec, name: str, xp=np):
    """The student's input `name` (INPUTS) of collected features."""
    parts = {"obs": ["obs"], "joints": ["obs", "joints"], "plan": ["obs", "plan"], "plan-wrist": ["obs", "plan-wrist"],
             "plan-fingers": ["obs", "plan-fingers"], "all": ["obs", "joints", "plan"]}
    return xp.concatenate([rec[p] for p in parts[name]], axis=-1)


def fit(x, y, steps: int = 6000, batch: int = 512, lr: float = 1e-3, seed: int = 0):
    """An MLP (512-256-128, ELU, inputs standardized) regressing y on x by Adam on the squared error:
    -> predict(x)."""
    import optax
    mean, std = x.mean(0), x.std(0) + 1e-6
    sizes = [x.shape[1], 512, 256, 128, y.shape[1]]
    keys = jax.random.split(jax.random.PRNGKey(seed), len(sizes))
    params = [(jax.random.normal(k, (a, b)) * np.sqrt(1.0 / a), jnp.zeros(b))
              for k, a, b in zip(keys, sizes[:-1], sizes[1:])]

    def net(params, x):
        h = (x - mean) / std
        for w, b in params[:-1]:
            h = jax.nn.elu(h @ w + b)
        return h @ params[-1][0] + params[-1][1]
    opt = optax.adam(optax.cosine_decay_schedule(lr, steps))
    state = opt.init(params)

    @jax.jit
    def update(params, state, idx):
        loss, g = jax.value_and_grad(lambda p: jnp.mean((net(p, x[idx]) - y[idx]) ** 2))(params)
        u, state = opt.update(g, state)
        return optax.apply_updates(params, u), state, loss
    x, y = jnp.asarray(x), jnp.asarray(y)
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        params, state, _ = update(params, state, jnp.asarray(rng.integers(0, len(x), batch)))
    return jax.jit(lambda x: net(params, x))


def rms_by_part(err):
    """rms of (n, 27) errors: wrist slides, wrist rotations, fingers, all."""
    parts = {"slides": slice(0, 3), "rotations": slice(3, 6), "fingers": slice(6, 27), "all": slice(0, 27)}
    return {k: float(np.sqrt((err[:, s] ** 2).mean())) for k, s in parts.items()}


def play_student(env, predict, name: str, envs: int, steps: int):
    """(per-note F1, notes, terminations) of the fitted MLP acting on `env`'s windows."""
    def act(s):
        return jnp.clip(predict(inputs(seen(env.base, s), name, jnp)[None])[0], -1.0, 1.0)
    return play(env, act, envs, steps)[0]


def fit_main(args, songs, cfg):
    from dexguitar import envs as E
    cut = args.songs * 3 // 4
    train_env, test_env = E.make("left", songs[:cut], cfg), E.make("left", songs[cut:], cfg)
    t0 = time.time()
    train = collect(train_env, args.envs, args.steps, args.noise, jax.random.PRNGKey(1))
    test = collect(test_env, args.envs, args.steps // 3, args.noise, jax.random.PRNGKey(2))
    print(f"{len(train['label'])} training and {len(test['label'])} held-out states ({time.time() - t0:.0f} s)",
          flush=True)
    for name in args.inputs:
        t0 = time.time()
        predict = fit(inputs(train, name), train["label"], steps=args.fit_steps)
        err = {k: np.asarray(predict(jnp.asarray(inputs(d, name)))) - d["label"]
               for k, d in (("train", train), ("held-out", test))}
        played = {k: play_student(e, predict, name, args.envs, args.steps // 3)
                  for k, e in (("train", train_env), ("held-out", test_env))}
        rms = "; ".join(f"{k}: " + ", ".join(f"{p} {v:.3f}" for p, v in rms_by_part(e).items()) for k, e in err.items())
        print(f"{name:7s} label rms {rms}", flush=True)
        print(f"{'':7s} closed-loop F1 " + "; ".join(f"{k} {f:.3f} over {n:.0f} notes, {t:.0f} terminations"
                                                    for k, (f, n, t) in played.items())
              + f" ({time.time() - t0:.0f} s)", flush=True)


SHIFT_FRAMES = 6                         # the first frames of a note: the hand moving to it


def drive(env, act, envs: int, steps: int):
    """Per step and env (steps, envs, ...): the action's departure from the teacher's label, the note's goal code and
    frame, and the per-note scores, `act(state)` driving the hand on training windows."""
    from dexguitar.music import cursor as CU
    base = env.base

    def record(s, a):
        return {"err": a - base.teacher(s), "goal": CU.current(s.cursor)[0], "note_frame": s.cursor.note_frame}
    key = jax.random.PRNGKey(0)
    return jax.tree.map(np.asarray, jax.jit(lambda key: rollout(env, act, envs, steps, (key, key), 0.0, record))(key))


def f1_by_kind(rec) -> dict:
    """Per-note F1 (and notes) by pressed strings and by the lowest pressed fret of the note closed."""
    goal, counted, f1 = rec["goal"], rec["counted"], rec["f1"]
    pressed = goal > 0
    n = pressed.sum(-1)
    low = np.where(pressed, goal, 99).min(-1)
    kinds = {"all": counted, "1 string": counted & (n == 1), "2 strings": counted & (n == 2),
             "3+ strings": counted & (n >= 3), "frets 1-4": counted & (low <= 4),
             "frets 5-9": counted & (low >= 5) & (low <= 9), "frets 10+": counted & (low >= 10) & (low < 99)}
    return {k: (float(f1[m].mean()) if m.any() else float("nan"), int(m.sum())) for k, m in kinds.items()}


def student_main(args, cfg):
    from dexguitar import envs as E
    from dexguitar.learn import policy as PO
    from dexguitar.music import procedural
    params, meta = PO.load(args.student)
    mean = PO.make_act(params, meta)
    cfg = dataclasses.replace(cfg, teacher_damping=C_WRIST, teacher_finger_damping=C_FINGER)
    sets = {"training": procedural.material("left", "general", 0, 256)[:args.songs],
            "held-out": procedural.material("left", "general", 1000, args.songs)}
    for name, songs in sets.items():
        env = E.make("left", songs, cfg)
        student, teacher, wrist = (lambda s: jnp.clip(mean(s.obs), -1.0, 1.0)), env.base.teacher, is_wrist()
        drivers = {"student": student, "teacher": teacher,
                   "student's wrist, teacher's fingers": lambda s: jnp.where(wrist, student(s), teacher(s)),
                   "teacher's wrist, student's fingers": lambda s: jnp.where(wrist, teacher(s), student(s))}
        for who, act in drivers.items():
            t0 = time.time()
            rec = drive(env, act, args.envs, args.steps)
            kinds = ", ".join(f"{k} {f:.3f} ({n})" for k, (f, n) in f1_by_kind(rec).items())
            print(f"{name} songs, {who}: F1 {kinds}; {int(rec['terminated'].sum())} terminations "
                  f"({time.time() - t0:.0f} s)", flush=True)
            if who != "student":
                continue
            err = rec["err"].reshape(-1, rec["err"].shape[-1])
            shift = (rec["note_frame"] < SHIFT_FRAMES).reshape(-1)
            for part, rows in (("all frames", slice(None)), (f"first {SHIFT_FRAMES} frames of a note", shift),
                               ("later frames", ~shift)):
                print(f"  student - label, rms on {part}: " + ", ".join(
                    f"{k} {v:.3f}" for k, v in rms_by_part(err[rows]).items()), flush=True)
            names = [env.base.model.actuator(i).name for i in range(err.shape[1])]
            worst = np.argsort(-np.sqrt((err ** 2).mean(0)))[:6]
            print("  largest: " + ", ".join(f"{names[i]} {np.sqrt((err[:, i] ** 2).mean()):.3f}" for i in worst),
                  flush=True)


def main():
    global C_WRIST, C_FINGER
    from dexguitar import envs as E
    from dexguitar.music import procedural
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hand", choices=("left", "right"), default="left",
                    help="right: the right planner's labels on held-out songs of the mixed material (seed 1000)")
    ap.add_argument("--songs", type=int, default=32)
    ap.add_argument("--envs", type=int, default=16)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--labels", nargs="+", choices=LABELS, default=list(LABELS))
    ap.add_argument("--play-noise", type=float, nargs="+", default=[0.0],
                    help="std of Gaussian noise added to each label's action while it plays")
    ap.add_argument("--c-wrist", type=float, default=C_WRIST, help="s: the wrist's velocity feedback (gain1d, damped)")
    ap.add_argument("--c-finger", type=float, default=C_FINGER, help="s: the fingers' velocity feedback")
    ap.add_argument("--noise-on", choices=NOISE_ON, default="all", help="the joints that --play-noise shakes")
    ap.add_argument("--fit", action="store_true", help="regress the labels from what a student sees (see above)")
    ap.add_argument("--inputs", nargs="+", choices=INPUTS, default=list(INPUTS))
    ap.add_argument("--noise", type=float, default=0.02, help="std of the noise added to the labels while collecting")
    ap.add_argument("--fit-steps", type=int, default=6000)
    ap.add_argument("--student", help="a trained left policy: where it departs from its teacher (see above)")
    args = ap.parse_args()
    C_WRIST, C_FINGER = args.c_wrist, args.c_finger
    cfg = E.EnvConfig(shift_prob=0.0, tempo_prob=0.0, teacher=True, physics="jax")
    if args.hand == "right" and (args.fit or args.student):
        ap.error("--fit and --student study the left hand")
    songs = (procedural.material("left", "general", 0, 256)[:args.songs] if args.hand == "left"
             else procedural.material("right", "mixed", 1000, args.songs))
    if args.fit:
        return fit_main(args, songs, cfg)
    if args.student:
        return student_main(args, cfg)
    env = E.make(args.hand, songs, cfg)
    base = env.base
    plan = base.plans[args.hand]
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
        played = play(env, label_fn(base, name), args.envs, args.steps, args.play_noise, args.noise_on)
        for noise, (f1, notes, terminations) in zip(args.play_noise, played):
            print(f"{name:7s} noise {noise:g} on {args.noise_on}: F1 {f1:.3f} over {notes:.0f} notes, "
                  f"{terminations:.0f} terminations", flush=True)
        print(f"{name:7s} {time.time() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
