"""Data-parallel training on 4 forced CPU devices (run by tests/test_devices.py in a process of its own, because the
device count is fixed when JAX starts): one `train` iteration of the shared tiny left-hand trainer (tests/tiny.py) on
4 devices, saved for the test to compare with its own one-device iteration and to resume on one device. Also a chunk
kept for one device, loaded from its file in this 4-device process, runs on that one device (by default JAX loads
an executable onto every device, and XLA aborted a 2-GPU run on a 4-GPU machine), and what `Placement.each` hands
each device. Prints one JSON line."""
import json
import re
import sys
from pathlib import Path

import jax
import jax.numpy as jnp

from dexguitar.learn import executable as X
from dexguitar.learn.devices import Placement
from dexguitar.learn.run import train

cache, out_dir = sys.argv[1], Path(sys.argv[2])
jax.config.update("jax_compilation_cache_dir", cache)
jax.config.update("jax_persistent_cache_min_compile_time_secs", 2.0)
sys.path.insert(0, str(Path(__file__).parent))
import tiny  # noqa: E402
from test_compile_once import StubTrainer  # noqa: E402

messages = []
train(tiny.left_trainer(), out_dir / "on4", iterations=1, devices=4, progress=False, log=messages.append)
# the rows of each matrix product through a 256-wide layer in the program one device runs
text = next(iter(X._LIVE.values())).as_text()
dot_rows = sorted({int(r) for r in re.findall(r"= f32\[(\d+),256\]\S* dot\(", text)})

# a one-device chunk kept in a file, then loaded from it as a later process would
X.directory = lambda: out_dir / "chunks"
state, data = jax.ShapeDtypeStruct((8,), jnp.float32), jnp.linspace(-1, 1, 8)
hows = []
for _ in range(2):
    X._LIVE.clear()
    chunk, _, how = X.ChunkBuild(StubTrainer(), Placement(1), 3, state, data).result()
    hows.append(how)
x = chunk(jnp.arange(8, dtype=jnp.float32) / 8, data)[0]

# each device's part alone: the first row of a part is the device's own
where = Placement(4)
each = jax.jit(where.each(lambda a: a - a[:1]))(jax.device_put(jnp.arange(8.0), where.split))
print(json.dumps({"each": each.tolist(), "each_devices": len(each.devices()),
                  "shardy": jax.config.jax_use_shardy_partitioner, "devices": len(jax.devices()),
                  "dot_rows": dot_rows, "stub": hows, "stub_out": x.tolist(),
                  "stub_devices": sorted(d.id for d in x.devices()),
                  "split": [m for m in messages if m.startswith("4 devices")],
                  "chunks": [m.split(" the training chunk")[0] for m in messages if "the training chunk" in m]}))
