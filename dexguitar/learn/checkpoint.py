"""Checkpoints through orbax: the whole `TrainState` (for --resume) and small policy exports (for eval, play, sync).

A run directory holds `ckpt/<iteration>/` (the last few full train states), `config.json` (how to rebuild the
trainer) and `metrics.jsonl`. An export (`policy/`) holds only what acting needs: the policy parameters, the
observation normalizer and the env sizes, a few MB."""
from __future__ import annotations

import json
from pathlib import Path

import jax
import numpy as np
import orbax.checkpoint as ocp


def _manager(directory: Path, keep: int = 2) -> ocp.CheckpointManager:
    return ocp.CheckpointManager(Path(directory).absolute(), options=ocp.CheckpointManagerOptions(
        max_to_keep=keep, create=True))


def _leaves(tree) -> dict:
    """The non-empty leaves of a pytree by position (orbax refuses zero-size arrays, e.g. MJX's empty `act`)."""
    return {f"{i:05d}": leaf for i, leaf in enumerate(jax.tree.leaves(tree)) if np.size(leaf) > 0}


def save(directory, step: int, state, keep: int = 2) -> None:
    """Save a pytree at `step` (blocking: when this returns the checkpoint is complete on disk)."""
    with _manager(directory, keep) as mngr:
        mngr.save(int(step), args=ocp.args.StandardSave(_leaves(state)), force=True)
        mngr.wait_until_finished()


def latest_step(directory) -> int | None:
    if not Path(directory).exists():
        return None
    with _manager(directory) as mngr:
        return mngr.latest_step()


def restore(directory, target, step: int | None = None):
    """Restore into the structure (and shardings) of `target`; its empty leaves are taken as they are."""
    with _manager(directory) as mngr:
        step = mngr.latest_step() if step is None else step
        if step is None:
            raise FileNotFoundError(f"no checkpoint in {directory}")
        restored = mngr.restore(step, args=ocp.args.StandardRestore(_leaves(target)))
    leaves, treedef = jax.tree.flatten(target)
    return jax.tree.unflatten(treedef, [restored.get(f"{i:05d}", leaf) for i, leaf in enumerate(leaves)])


def export_policy(directory, params, obs_norm, meta: dict) -> None:
    directory = Path(directory).absolute()
    directory.mkdir(parents=True, exist_ok=True)
    save(directory / "params", int(meta.get("iteration", 0)), {"policy": params, "obs_norm": obs_norm}, keep=1)
    (directory / "policy.json").write_text(json.dumps(meta, indent=2))


def load_policy(directory):
    """(params {"policy", "obs_norm"}, meta) of an exported policy; the structure is rebuilt from the meta."""
    directory = Path(directory).absolute()
    meta_path = directory / "policy.json"
    if not meta_path.exists():
        raise FileNotFoundError(f"{directory}: not an exported policy (no policy.json)")
    meta = json.loads(meta_path.read_text())
    from dexguitar.envs.core import HISTORY
    from dexguitar.learn import networks as N
    frame = (meta["obs_size"] - meta["goal_size"]) // HISTORY
    target = {"policy": N.init_params(N.Policy(meta["action_size"]), jax.random.PRNGKey(0), (HISTORY, frame),
                                      (meta["goal_size"],)),
              "obs_norm": N.normalizer_init(frame)}
    return restore(directory / "params", target), meta
