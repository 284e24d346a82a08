"""Data parallelism (issue #12) on 4 forced CPU devices, in a process of its own (tests/devices_check.py): one
iteration on 4 devices equals the one-device iteration up to the order of float sums, and a run saved on 4 devices
resumes on 1."""
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CACHE = Path(os.environ.get("DEXGUITAR_TEST_CACHE", ROOT / ".cache" / "xla"))      # as tests/conftest.py


def test_four_devices_match_one_and_a_four_device_run_resumes_on_one(tmp_path):
    """Also: a program kept for fewer devices than the machine has loads onto those devices (a 2-GPU run on a
    4-GPU machine aborted in XLA when it loaded its chunk onto all 4)."""
    flags = (os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=4").strip()  # + conftest's
    env = dict(os.environ, XLA_FLAGS=flags, JAX_PLATFORMS="cpu")
    done = subprocess.run([sys.executable, str(ROOT / "tests" / "devices_check.py"), str(CACHE), str(tmp_path / "run")],
                          env=env, cwd=ROOT, capture_output=True, text=True, timeout=1500)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["devices"] == 4
    assert out["split"] == ["4 devices: 1 envs and minibatches of 2 samples each"]
    assert out["chunks"][2] == "reused"              # the resumed run plays the 1-device run's program
    assert out["chunks"][3] == "loaded" and out["later"] == 1    # ... and so does a later run, loaded from its file
    assert out["moved"] > 1e-4                       # the update did change the parameters ...
    assert out["max_diff"] < 1e-5                    # ... and identically on 1 and 4 devices (atol 1e-5)
    # a minibatch of 8 samples: one device multiplies all 8 rows through the networks, each of 4 devices 2 of them
    # (before the update's minibatches were split, every device computed all 8)
    assert 8 in out["dot_rows"]["1"] and 8 not in out["dot_rows"]["4"] and 2 in out["dot_rows"]["4"]
    assert out["iterations"] == [1, 2] and out["second"] == 2
