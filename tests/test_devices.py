"""Data parallelism on 4 forced CPU devices: one iteration of the shared tiny left-hand trainer on 4 devices
(tests/devices_check.py, in a process of its own), each device stepping its own envs, equals the one-device iteration
of this process up to the order of float sums, and the 4-device run resumes here on one device."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np

from dexguitar.learn import checkpoint as C
from dexguitar.learn import executable as X
from dexguitar.learn import run as RUN

ROOT = Path(__file__).resolve().parents[1]
CACHE = Path(os.environ.get("DEXGUITAR_TEST_CACHE") or ROOT / ".cache" / "xla")      # as tests/conftest.py


def test_four_devices_match_one_and_a_four_device_run_resumes_on_one(left_trainer, tmp_path, monkeypatch):
    flags = (os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=4").strip()  # + conftest's
    env = dict(os.environ, XLA_FLAGS=flags, JAX_PLATFORMS="cpu")
    done = subprocess.run([sys.executable, str(ROOT / "tests" / "devices_check.py"), str(CACHE), str(tmp_path)],
                          env=env, cwd=ROOT, capture_output=True, text=True, timeout=1500)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["devices"] == 4 and out["chunks"] in (["compiled"], ["loaded"])     # loaded: a cache of a run before
    assert out["split"] == ["4 devices: 1 envs and minibatches of 2 samples each"]
    # `Placement.each`: every device computes on its own 2 of 8 rows (a - its first row), and the parts stay put
    assert out["each"] == [0, 1] * 4 and out["each_devices"] == 4
    assert out["shardy"] is False                # several devices: XLA's GSPMD partitions (`Placement`)
    # the one-device chunk runs from its file on the first device alone
    assert out["stub"] == ["compiled", "loaded"] and out["stub_devices"] == [0]
    x, data = np.arange(8, dtype=np.float32) / 8, np.linspace(-1, 1, 8, dtype=np.float32)
    for _ in range(3):
        x = np.tanh(x * 2.0 + data)
    np.testing.assert_allclose(out["stub_out"], x, rtol=1e-5)

    messages, built, result = [], [], X.ChunkBuild.result
    monkeypatch.setattr(X.ChunkBuild, "result", lambda build: built.append(result(build)) or built[-1])
    RUN.train(left_trainer, tmp_path / "on1", iterations=1, devices=1, progress=False, log=messages.append)
    start = left_trainer.init()
    params = {n: jax.device_get(C.restore(tmp_path / f"on{n}" / "ckpt", start)[0].params) for n in (1, 4)}
    leaves = {n: [np.asarray(a) for a in jax.tree.leaves(p)] for n, p in params.items()}
    moved = max(float(np.abs(a - np.asarray(b)).max()) for a, b in zip(leaves[1], jax.tree.leaves(start.params)))
    diff = max(float(np.abs(a - b).max()) for a, b in zip(leaves[1], leaves[4]))
    assert moved > 1e-4                          # the update did change the parameters ...
    assert diff < 1e-5                           # ... and identically on 1 and 4 devices (atol 1e-5)
    # PPO's minibatch of 8 samples and the discriminator's batch of 16: one device multiplies all their rows through
    # the networks, each of 4 devices a quarter of them (2 and 4)
    ((chunk, _, _),) = built                     # this run's program
    rows = sorted({int(r) for r in re.findall(r"= f32\[(\d+),256\]\S* dot\(", chunk.as_text())})
    assert {8, 16} <= set(rows) and 2 not in rows
    assert {2, 4} <= set(out["dot_rows"]) and 16 not in out["dot_rows"]

    # the 4-device run goes on here, on one device, with the one-device run's program
    messages.clear()
    second = RUN.train(left_trainer, tmp_path / "on4", iterations=2, devices=1, resume=True, progress=False,
                       log=messages.append)
    assert any(m.startswith("reused the training chunk") for m in messages)
    rows = [json.loads(r) for r in (tmp_path / "on4" / "metrics.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [1, 2] and second["iteration"] == 2
