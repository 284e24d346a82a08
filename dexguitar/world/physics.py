"""The one physics step of every env, benchmark and check: PD targets held for `SUBSTEPS` MJX steps (240 Hz physics
under 60 Hz control), and the matmul precision of everything an env computes."""
from __future__ import annotations

import functools

import jax

from dexguitar import mjx as _quiet_mjx
from dexguitar.world.scene import SUBSTEPS

mjx = _quiet_mjx()

# A GPU's default float32 matmul is TF32 (a 10-bit mantissa, relative error 2^-11): a point half a metre from the
# origin moves by a quarter of a millimetre, a fair part of a press's depth. On an H100 a zero-residual left hand
# played snow at F1 0.924 with TF32 and 0.990 in full float32, as on the CPU (turkish_march 0.974 and 0.993;
# docs/benchmarks.md, "Float32 in the env"). Networks keep the default: only the world needs it.
PRECISION = "highest"


def exact(fn):
    """`fn` traced with full float32 matmuls (a no-op on the CPU, whose float32 matmuls are exact already)."""
    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        with jax.default_matmul_precision(PRECISION):
            return fn(*args, **kwargs)
    return wrapped


@exact
def control_step(mjx_model, data, ctrl, substeps: int = SUBSTEPS):
    """Advance `data` by one control step with the actuators' targets set to `ctrl`."""
    data = data.replace(ctrl=ctrl)
    return jax.lax.fori_loop(0, substeps, lambda _, d: mjx.step(mjx_model, d), data)
