"""Test-wide settings: a persistent XLA compilation cache, so that a computation compiled by one test (or an earlier
run of the suite) is not compiled again by the next one; the suite is dominated by compiling the scanned envs."""
import os
from pathlib import Path

import jax

CACHE = Path(os.environ.get("DEXGUITAR_TEST_CACHE", Path(__file__).resolve().parent.parent / ".cache" / "xla"))
jax.config.update("jax_compilation_cache_dir", str(CACHE))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 2.0)
