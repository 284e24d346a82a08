"""XLA:CPU waits forever on two independent batched Cholesky factorizations (jaxlib 0.10.2, 2 cores): each runs on
one of the intra-op pool's threads and waits there for its batch's pieces, scheduled on the same pool
(`jax::ParallelBatchMap`, seen with gdb). MJX factorizes the mass matrix and its Newton step with them, so `dexguitar
sync --envs 512` on this 2-core CPU never returned from its first chunk call; `train` warns from 512 envs on a CPU.

    JAX_PLATFORMS=cpu timeout 60 python experiments/cpu_lapack_hang.py 512     # returns
    JAX_PLATFORMS=cpu timeout 60 python experiments/cpu_lapack_hang.py 4096    # hangs (rc 124), also with
                                                      # XLA_FLAGS=--xla_cpu_multi_thread_eigen=false
"""
import sys

import jax
import jax.numpy as jnp

n = int(sys.argv[1]) if len(sys.argv) > 1 else 4096
A = jnp.eye(30)[None].repeat(n, 0) * 2.0
B = jnp.ones((n, 30))


def solve(a):
    low = jax.vmap(jnp.linalg.cholesky)(a)
    return jax.vmap(lambda lo, b: jax.scipy.linalg.cho_solve((lo, True), b))(low, B)


def body(c, _):
    x, y = solve(A + c), solve(A * 1.5 + c)          # two independent batched factorizations
    return c + 1e-3 * (x.mean() + y.mean()), x.sum() + y.sum()


print(n, float(jax.jit(lambda: jax.lax.scan(body, 0.0, None, length=4)[1].sum())()))
