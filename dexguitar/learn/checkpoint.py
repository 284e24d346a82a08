"""Checkpoints through orbax: the whole `TrainState` (for --resume) and small policy exports (for eval, play, sync).

A run directory holds `ckpt/<iteration>/` (the last few full train states), `config.json` (how to rebuild the
trainer) and `metrics.jsonl`. An export (`policy/`) holds only what acting needs: the policy parameters, the
observation normalizer and the env sizes, a few MB; a synchronizer's export names the two policies it shifts."""
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
    """Write `params` + `obs_norm` and `policy.json`."""
    directory = Path(directory).absolute()
    directory.mkdir(parents=True, exist_ok=True)
    save(directory / "params", int(meta.get("iteration", 0)), {"policy": params, "obs_norm": obs_norm}, keep=1)
    (directory / "policy.json").write_text(json.dumps(meta, indent=2))


def _policy_target(meta: dict) -> dict:
    """The parameter structure of an export, rebuilt from its meta: a single-hand policy or a synchronizer."""
    from dexguitar.envs.core import HISTORY
    from dexguitar.learn import networks as N
    if meta.get("kind") == "synchronizer":
        from dexguitar.learn.sync import HAND_GOAL, init_synchronizer
        hand = {"action_size": meta["action_size"] // 2, "goal_size": HAND_GOAL,
                "obs_size": (meta["obs_size"] - meta["goal_size"]) // 2 + HAND_GOAL}
        frozen = _policy_target(hand)
        params, norm = init_synchronizer(jax.random.PRNGKey(0), frozen, frozen)
        return {"policy": params, "obs_norm": norm}
    frame = (meta["obs_size"] - meta["goal_size"]) // HISTORY
    return {"policy": N.init_params(N.Policy(meta["action_size"]), jax.random.PRNGKey(0), (HISTORY, frame),
                                    (meta["goal_size"],)),
            "obs_norm": N.normalizer_init(frame)}


def export_dir(directory) -> Path:
    """An exported policy's directory: `directory` itself, or the `policy/` export of a run directory."""
    directory = Path(directory)
    if not (directory / "policy.json").exists() and (directory / "policy" / "policy.json").exists():
        return directory / "policy"
    return directory


def load_policy(directory):
    """(params {"policy", "obs_norm"}, meta) of an exported policy. A synchronizer's export holds the synchronizer
    alone and names the two policies it was trained with (`sources`, paths as given to `dexguitar sync`); they are
    loaded into params["frozen"]."""
    directory = Path(directory).absolute()
    meta_path = directory / "policy.json"
    if not meta_path.exists():
        raise FileNotFoundError(f"{directory}: not an exported policy (no policy.json)")
    meta = json.loads(meta_path.read_text())
    params = restore(directory / "params", _policy_target(meta))
    if meta.get("kind") == "synchronizer":
        params["frozen"] = {}
        for side, source in meta["sources"].items():
            path = Path(source["path"])
            if not (path / "policy.json").exists():
                raise FileNotFoundError(f"{directory}: the {side}-hand policy it synchronizes, {path}, is missing "
                                        f"(paths are relative to the directory `dexguitar sync` ran in)")
            params["frozen"][side] = load_policy(path)[0]
    return params, meta
