"""How large the left hand's programs are and how long XLA takes to compile each alone, in a fresh process with JAX's
cache off: jaxpr equations, optimized HLO instructions, fusions, trace / lower / compile seconds.

    XLA_FLAGS=--xla_gpu_enable_triton_gemm=false python experiments/program_size.py chunk   # or nodisc, rollout,
                                                                                           # first-state, nets, reset
`nodisc`: the chunk of the same trainer without a reference motion (no discriminators). `first-state` is
`Trainer.initial_state` as one program; `nets` and `reset` its networks' initializers and its env reset apart.
"""
import argparse
import time

import jax

from dexguitar.configs import load_config
from dexguitar.learn import imitation as IM
from dexguitar.learn import networks as N
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import library
from dexguitar.music import timeline as TL


def equations(jaxpr) -> int:
    n = 0
    for e in jaxpr.eqns:
        subs = [getattr(q, "jaxpr", q) for p in e.params.values() for q in (p if isinstance(p, (tuple, list)) else [p])]
        subs = [j for j in subs if hasattr(j, "eqns")]
        n += sum(equations(j) for j in subs) if subs else 1
    return n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["chunk", "nodisc", "rollout", "first-state", "nets", "reset"])
    ap.add_argument("--song", default="minuet_in_g")
    ap.add_argument("--config", default="left_finetune")
    ap.add_argument("--physics", default="warp")
    args = ap.parse_args()
    jax.config.update("jax_enable_compilation_cache", False)
    cfg, env_cfg = load_config(args.config, [f"env.physics={args.physics}"], hand="left")
    ref = None if args.what == "nodisc" else reference_frames(load_motion("left"))
    tr = Trainer(cfg, [TL.from_song(s) for s in library.load_songs([args.song])], ref, env_cfg)
    key, inputs = jax.random.PRNGKey(0), tr.init_inputs()

    def nets(k, inputs):
        k1, k2, k3 = jax.random.split(k, 3)
        frames = (tr.layout.history, tr.layout.frame_size)
        return (tr.init_policy(k1, inputs)[0],
                N.init_params(tr.critic, k2, frames, (tr.layout.goal_size + tr.layout.privileged,)),
                {n: N.init_params(tr.disc, k3, (IM.FRAMES, d.features)) for n, d in tr.disc_specs.items()})
    programs = {
        "chunk": lambda: tr.make_train_chunk(1).trace(tr.state_shapes, tr.data),
        "nodisc": lambda: tr.make_train_chunk(1).trace(tr.state_shapes, tr.data),
        "rollout": lambda: jax.jit(lambda ts: tr.rollout(tr.env, ts, ts.key)).trace(tr.state_shapes),
        "first-state": lambda: jax.jit(tr.initial_state).trace(key, inputs),
        "nets": lambda: jax.jit(nets).trace(key, inputs),
        "reset": lambda: jax.jit(lambda k, i: jax.vmap(tr.env.bind(i["songs"]).reset)(
            jax.random.split(k, cfg.num_envs))).trace(key, inputs),
    }
    t = time.perf_counter()
    traced = programs[args.what]()
    t_trace = time.perf_counter() - t
    t = time.perf_counter()
    lowered = traced.lower()
    t_lower = time.perf_counter() - t
    t = time.perf_counter()
    text = lowered.compile().as_text()
    t_compile = time.perf_counter() - t
    print(f"{args.what} ({tr.env.physics}, {cfg.num_envs} envs): {equations(traced.jaxpr.jaxpr):,} jaxpr equations, "
          f"{sum(' = ' in line for line in text.splitlines()):,} HLO instructions, {text.count(' fusion('):,} fusions; "
          f"trace {t_trace:.1f} s, lower {t_lower:.1f} s, XLA compile {t_compile:.1f} s")


if __name__ == "__main__":
    main()
