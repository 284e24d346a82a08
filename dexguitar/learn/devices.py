"""Where a run's arrays live, on one device or many."""
from __future__ import annotations

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from dexguitar.errors import UserError


class Placement:
    """Where a run's arrays live: a mesh over `devices` devices (default: every device, on every host when started
    with `jax.distributed`). Env states are split along the envs; everything else (parameters, optimizer states,
    normalizers, replay buffers, the songs) is replicated, so XLA computes each device's envs where they live, splits
    each PPO minibatch over the devices (`split`) and reduces gradients and statistics across them: one iteration on
    N devices is the one-device iteration, up to the order of float sums."""

    def __init__(self, devices: int | None = None):
        found = jax.devices()
        self.n = devices or len(found)
        if self.n > len(found):
            raise UserError(f"--devices {self.n}: there are {len(found)} {found[0].platform} device(s)")
        self.mesh = Mesh(np.array(found[:self.n]), ("envs",))
        if self.n > 1:
            # XLA's GSPMD partitions the programs, not Shardy (JAX's default): with the envs stepped per device
            # (`each`) inside the training chunk, XLA's GPU compile of the chunk crashed with a segmentation fault
            # under Shardy on 2 H200s (JAX 0.11.2, either physics) and compiled under GSPMD
            # (docs/benchmarks.md, "Several GPUs")
            jax.config.update("jax_use_shardy_partitioner", False)
        self.main = jax.process_index() == 0          # only the first process writes files

    def shardings(self, state):
        """The sharding of every leaf of a `TrainState`: the env states split along their first axis (the envs; for
        MJX's Warp buffers outside the env batch, `world.physics.shared`, the devices: each device's own buffers,
        joined, as `Trainer.reset_envs` makes them), everything else whole."""
        return jax.tree.map(lambda _: self.whole, state).replace(env=jax.tree.map(lambda _: self.split, state.env))

    def each(self, fn):
        """`fn`, a function of env-split pytrees, run by every device on its own part (`shard_map`): MJX's Warp
        steps a device's envs with that device's buffers (a custom call that XLA cannot split would gather all the
        envs onto every device). One device: `fn` itself."""
        if self.n == 1:
            return fn
        return jax.shard_map(fn, mesh=self.mesh, in_specs=PartitionSpec("envs"), out_specs=PartitionSpec("envs"),
                             check_vma=False)

    def placed_shapes(self, shapes):
        """A `TrainState`'s shapes (`jax.eval_shape`) with this placement's shardings: what a program is lowered
        with before the state exists."""
        return jax.tree.map(lambda s, sharding: jax.ShapeDtypeStruct(s.shape, s.dtype, sharding=sharding), shapes,
                            self.shardings(shapes))

    def replicated(self, tree):
        return jax.tree.map(lambda _: self.whole, tree)

    def put(self, tree, shardings):
        """Place a pytree that every process holds whole (the same seed gives the same values everywhere)."""
        def one(x, sharding):
            host = np.asarray(x)
            return jax.make_array_from_callback(host.shape, sharding, lambda index: host[index])
        return jax.tree.map(one, tree, shardings)

    @property
    def split(self) -> NamedSharding:
        """Split along the first axis (envs, or the samples of a minibatch) over the devices of the mesh."""
        return NamedSharding(self.mesh, PartitionSpec("envs"))

    @property
    def steps(self) -> NamedSharding:
        """Split along the second axis over the devices: a rollout's arrays (steps, envs, ...) between the stages of
        an iteration (`learn.stages`)."""
        return NamedSharding(self.mesh, PartitionSpec(None, "envs"))

    @property
    def whole(self) -> NamedSharding:
        """Replicated on every device of the mesh."""
        return NamedSharding(self.mesh, PartitionSpec())
