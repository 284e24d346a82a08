"""Where a training iteration's time goes: the rollout (the vmapped env and policy, `horizon` steps) against the whole
iteration (rollout, discriminators, GAE, PopArt, PPO epochs), each timed over one chunk of `iterations_per_call`
iterations, compilation apart. Prints one JSON line: seconds per iteration of each, the update's share (their
difference) and samples/s.

    .venv/bin/python experiments/iteration_split.py --hand left --procedural 8 --config left_general --physics warp
    .venv/bin/python experiments/iteration_split.py --hand duet --song strum_g_c_d --config sync_gpu \\
        --left models/policies/left_strum_g_c_d --right models/policies/right_patterns --physics jax
"""
import argparse
import json
import sys
import time

import jax

from dexguitar import envs as E
from dexguitar.configs import load_config
from dexguitar.learn import policy as PO
from dexguitar.learn.devices import Placement
from dexguitar.learn.run import chunk_build, compilation_cache
from dexguitar.learn.sync import SyncTrainer
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import library, procedural
from dexguitar.music import timeline as TL


def timed(step, state) -> float:
    """Seconds of the second of two calls of `step` (state -> (state, metrics)), the first one's state going on: the
    first call pays for loading and warming up."""
    state = jax.block_until_ready(step(state)[0])
    t = time.perf_counter()
    jax.block_until_ready(step(state))
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hand", default="left", choices=("left", "right", "duet"))
    ap.add_argument("--config", required=True)
    ap.add_argument("--song", nargs="*", default=[])
    ap.add_argument("--procedural", type=int, default=8)
    ap.add_argument("--style")
    ap.add_argument("--left")
    ap.add_argument("--right")
    ap.add_argument("--physics", default="auto", choices=E.PHYSICS)
    args = ap.parse_args()
    compilation_cache()
    cfg, env = load_config(args.config, [f"env.physics={args.physics}"], hand=args.hand)
    songs = (library.load_songs(args.song) if args.song else
             procedural.material(args.hand, args.style or ("general" if args.hand == "left" else None), 0,
                                 args.procedural))
    timelines = [TL.from_song(s) for s in songs]
    where = Placement(1)
    if args.hand == "duet":
        trainer = SyncTrainer(cfg, timelines, reference_frames(load_motion("left")),
                              *PO.load_pair(args.left, args.right), env, devices=1)
    else:
        trainer = Trainer(cfg, timelines, reference_frames(load_motion(args.hand)), env, devices=1)
    data = where.put(trainer.data, where.replicated(trainer.data))
    chunk, compile_s, how = chunk_build(trainer, where, data, lambda msg: print(msg, file=sys.stderr)).result()
    state = trainer.init()
    n = cfg.iterations_per_call

    def rollouts(ts, data):
        env_ = trainer.env.bind(data.songs)

        def one(ts, _):
            key, k_roll = jax.random.split(ts.key)
            env_state, traj = trainer.rollout(env_, ts, k_roll)
            return ts.replace(env=env_state, key=key), traj["reward"].sum()
        return jax.lax.scan(one, ts, None, length=n)
    t = time.perf_counter()
    rollout = jax.jit(rollouts).lower(state, data).compile()
    rollout_compile_s = time.perf_counter() - t
    rollout_s = timed(lambda s: rollout(s, data), state)
    chunk_s = timed(lambda s: chunk(s, data), state)          # the chunk donates its state: last
    print(json.dumps({
        "hand": args.hand, "config": args.config, "physics": trainer.env.physics, "envs": cfg.num_envs,
        "samples_per_iteration": cfg.batch, "chunk": how, "chunk_ready_s": round(compile_s, 2),
        "rollout_compile_s": round(rollout_compile_s, 2), "iteration_s": chunk_s / n, "rollout_s": rollout_s / n,
        "update_s": (chunk_s - rollout_s) / n, "rollout_share": rollout_s / chunk_s,
        "samples_per_s": n * cfg.batch / chunk_s, "device": jax.devices()[0].device_kind}))


if __name__ == "__main__":
    main()
