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
        self.main = jax.process_index() == 0          # only the first process writes files

    def shardings(self, state):
        """The sharding of every leaf of a `TrainState`. The env states' scalars are whole: MJX's Warp Data holds
        sizes outside the env batch (its contact buffer's, `world.physics.shared`), and Warp runs on one device."""
        return jax.tree.map(lambda _: self.whole, state).replace(
            env=jax.tree.map(lambda x: self.split if len(x.shape) else self.whole, state.env))

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
    def whole(self) -> NamedSharding:
        """Replicated on every device of the mesh."""
        return NamedSharding(self.mesh, PartitionSpec())
