"""The host side of training: build a trainer from a config, resume, run scanned chunks, show progress, write
metrics and checkpoints. The host only logs and saves; all learning happens inside the jitted chunk."""
from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path

import jax
import numpy as np

from dexguitar.learn import checkpoint as C
from dexguitar.learn.trainer import Trainer, TrainConfig

SUMMED = ("episodes", "terminations")      # counts (and notes/*); f1/* are sums over notes; the rest are means


def chunk_summary(metrics: dict, n_iter: int) -> dict:
    m = {k: float(v) for k, v in metrics.items()}
    out = {k: m[k] for k in m if k in SUMMED or k.startswith("notes/")}
    for k, v in m.items():
        if k.startswith("f1/"):
            notes = m.get("notes/" + k[3:], 0.0)
            out[k] = v / notes if notes > 0 else float("nan")
        elif k not in out:
            out[k] = v / n_iter
    return out


def train(trainer: Trainer, out_dir, *, iterations: int, resume: bool = False, progress: bool = True,
          meta: dict | None = None, stop_after_calls: int | None = None, max_minutes: float | None = None,
          init_from=None) -> dict:
    """Run until `iterations` iterations are done (counting those of a resumed run). Returns the last summary."""
    cfg = trainer.config
    out = Path(out_dir)
    ckpt_dir = out / "ckpt"
    state = trainer.init()
    if init_from and C.latest_step(ckpt_dir) is None:
        params, meta_init = C.load_policy(C.export_dir(init_from))
        if meta_init["hand"] != cfg.hand:
            raise SystemExit(f"--init-from {init_from}: a {meta_init['hand']} hand policy, not {cfg.hand}")
        state = state.replace(params=dict(state.params, policy=params["policy"]), obs_norm=params["obs_norm"])
        print(f"policy initialized from {init_from} ({meta_init.get('samples', 0):,} samples)", file=sys.stderr)
    if C.latest_step(ckpt_dir) is not None:
        if not resume:
            raise SystemExit(f"{out} already holds a run: pass --resume to continue it, or choose another --out")
        state = C.restore(ckpt_dir, state)
        print(f"resumed {out} at iteration {int(state.iteration)}", file=sys.stderr)
    out.mkdir(parents=True, exist_ok=True)
    (out / "config.json").write_text(json.dumps({"train": dataclasses.asdict(cfg),
                                                 "env": dataclasses.asdict(trainer.env.config),
                                                 "columns": trainer.columns, **(meta or {})}, indent=2))
    n = cfg.iterations_per_call
    chunk = trainer.make_train_chunk(n)
    start_iter = int(state.iteration)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=iterations, initial=start_iter, unit="it", dynamic_ncols=True, file=sys.stderr)
    summary, calls, t_start = {}, 0, time.perf_counter()
    samples_done = 0
    with open(out / "metrics.jsonl", "a") as log:
        while int(state.iteration) < iterations:
            t0 = time.perf_counter()
            state, metrics = chunk(state)
            metrics = jax.device_get(metrics)
            dt = time.perf_counter() - t0
            it = int(state.iteration)
            summary = chunk_summary(metrics, n)
            summary.update(iteration=it, samples=it * cfg.batch, seconds=dt, samples_per_s=n * cfg.batch / dt,
                           wall=time.perf_counter() - t_start)
            log.write(json.dumps(summary) + "\n")
            log.flush()
            C.save(ckpt_dir, it, state)
            export(trainer, state, out / "policy")
            calls += 1
            samples_done += n * cfg.batch
            if bar is not None:
                hands = trainer.env.roles + (("both",) if len(trainer.env.roles) == 2 else ())
                reward = np.mean([v for k, v in summary.items() if k.startswith("reward/")])
                bar.set_postfix({"samples/s": f"{summary['samples_per_s']:,.0f}",
                                 **{f"F1 {h}": f"{summary.get('f1/' + h, float('nan')):.3f}" for h in hands},
                                 "reward": f"{reward:.3f}"})
                bar.update(n)
            if stop_after_calls is not None and calls >= stop_after_calls:
                break
            if max_minutes is not None and time.perf_counter() - t_start > 60 * max_minutes:
                print(f"stopping after {max_minutes} minutes at iteration {it} (resume with --resume)",
                      file=sys.stderr)
                break
    if bar is not None:
        bar.close()
    return summary


def load_config(path: str | None, **overrides):
    """(TrainConfig, EnvConfig or None) from an experiments/*.py file defining CONFIG (and optionally ENV), with
    TrainConfig fields overridden by name."""
    cfg, env = TrainConfig(), None
    if path:
        import runpy
        ns = runpy.run_path(path)
        cfg, env = ns.get("CONFIG", cfg), ns.get("ENV")
    fields = {f.name for f in dataclasses.fields(TrainConfig)}
    cfg = dataclasses.replace(cfg, **{k: v for k, v in overrides.items() if k in fields and v is not None})
    return cfg, env



def export(trainer: Trainer, state, directory) -> None:
    """What eval and play need: the policy (or the synchronizer, naming its two frozen policies), its observation
    normalizer and the env sizes."""
    env = trainer.env
    frozen = state.params.get("frozen")
    meta = {"hand": trainer.config.hand, "kind": "synchronizer" if frozen is not None else "policy",
            "action_size": env.action_size, "goal_size": env.goal_size, "obs_size": env.obs_size,
            "iteration": int(state.iteration), "samples": int(state.iteration) * trainer.config.batch,
            "columns": list(trainer.columns)}
    if frozen is not None:
        meta["sources"] = {side: {k: m.get(k) for k in ("path", "samples", "iteration")}
                           for side, m in trainer.sources.items()}
    C.export_policy(directory, state.params["policy"], state.obs_norm, meta)


def policy_from(directory, synchronized: bool = True):
    """(act, meta) from an exported policy or a run directory (its `policy/`): act(obs) -> mean action. For a
    synchronizer, act plays both hands on duet observations (synchronized=False: without the latent shift)."""
    from dexguitar.envs.core import HISTORY
    from dexguitar.learn import networks as N
    params, meta = C.load_policy(C.export_dir(directory))
    if meta.get("kind") == "synchronizer":
        from dexguitar.learn.sync import players
        return players(params)[int(synchronized)], meta
    policy = N.Policy(meta["action_size"])

    def act(obs):
        frames, goal = N.split_obs(obs, HISTORY, meta["goal_size"])
        mu, _ = policy.apply(params["policy"], N.normalize(params["obs_norm"], frames), goal)
        return mu
    return act, meta
