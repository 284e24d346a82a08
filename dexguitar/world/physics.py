"""The one physics step of every env, benchmark and check: PD targets held for `SUBSTEPS` MJX steps (240 Hz physics
under 60 Hz control)."""
from __future__ import annotations

import jax

from dexguitar import mjx as _quiet_mjx
from dexguitar.world.scene import SUBSTEPS

mjx = _quiet_mjx()


def control_step(mjx_model, data, ctrl, substeps: int = SUBSTEPS):
    """Advance `data` by one control step with the actuators' targets set to `ctrl`."""
    data = data.replace(ctrl=ctrl)
    return jax.lax.fori_loop(0, substeps, lambda _, d: mjx.step(mjx_model, d), data)
