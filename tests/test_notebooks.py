"""The Colab notebooks in experiments/ run top to bottom: each one's code cells, joined, in a fresh Python process in
its tiny configuration (DEXGUITAR_NOTEBOOK_TINY=1: the CPU config, 1 iteration, a 3-note song), sharing the suite's
XLA compilation cache. They are written by experiments/make_notebooks.py."""
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = ROOT / "experiments"
CACHE = Path(os.environ.get("DEXGUITAR_TEST_CACHE", ROOT / ".cache" / "xla"))     # as in conftest.py
NAMES = ("train_a_hand", "synchronize", "play_and_listen")


def cells(name: str, kind: str = "code") -> list[str]:
    nb = json.loads((NOTEBOOKS / f"{name}.ipynb").read_text())
    assert nb["nbformat"] == 4
    return ["".join(c["source"]) if isinstance(c["source"], list) else c["source"]
            for c in nb["cells"] if c["cell_type"] == kind]


def run_notebook(name: str, out: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    code = "\n\n".join(cells(name))
    env = dict(os.environ, DEXGUITAR_NOTEBOOK_TINY="1", DEXGUITAR_NOTEBOOK_OUT=str(out), JAX_PLATFORMS="cpu",
               JAX_COMPILATION_CACHE_DIR=str(CACHE), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="2",
               DEXGUITAR_CACHE=str(CACHE))          # the commands' own cache setting (cli.compilation_cache)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], check=False, cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=timeout)
    print(f"{name}: {time.perf_counter() - t0:.1f} s")
    return proc


def check(proc: subprocess.CompletedProcess) -> str:
    if proc.returncode != 0:
        pytest.fail(f"exit {proc.returncode}\n--- stdout\n{proc.stdout[-4000:]}\n--- stderr\n{proc.stderr[-4000:]}")
    return proc.stdout


@pytest.mark.parametrize("name", NAMES)
def test_notebook_is_plain_python_without_outputs(name):
    nb = json.loads((NOTEBOOKS / f"{name}.ipynb").read_text())
    assert nb["cells"][0]["cell_type"] == "markdown" and nb["cells"][1]["cell_type"] == "code"
    assert "TINY" in cells(name)[0] and "google.colab" in cells(name)[0]
    for c in nb["cells"]:
        if c["cell_type"] == "code":
            assert c["outputs"] == [] and c["execution_count"] is None
    for source in cells(name):
        compile(source, name, "exec")
        magics = [line for line in source.splitlines() if line.lstrip().startswith(("!", "%"))]
        assert not magics, magics


def test_train_a_hand(tmp_path):
    out = check(run_notebook("train_a_hand", tmp_path))
    run = tmp_path / "runs" / "left"
    assert len((run / "metrics.jsonl").read_text().splitlines()) == 1
    assert json.loads((run / "policy" / "policy.json").read_text())["hand"] == "left"
    assert "two notes and a chord: left F1" in out               # the evaluation
    assert (tmp_path / "f1.png").stat().st_size > 0


def test_synchronize(tmp_path):
    out = check(run_notebook("synchronize", tmp_path))
    run = tmp_path / "runs" / "sync-strum"
    assert json.loads((run / "policy" / "policy.json").read_text())["kind"] == "synchronizer"
    assert len((run / "metrics.jsonl").read_text().splitlines()) == 1
    assert "[before synchronization] two notes and a chord" in out
    assert "[after synchronization] two notes and a chord" in out


def test_play_and_listen(tmp_path, offscreen_gl):
    out = check(run_notebook("play_and_listen", tmp_path))
    prefix = tmp_path / "out" / "demo"
    assert prefix.with_suffix(".wav").stat().st_size > 44
    assert prefix.with_suffix(".mp4").exists() or prefix.with_suffix(".png").exists()
    report = json.loads(Path(str(prefix) + "-report.json").read_text())
    assert set(report["summary"]) >= {"left", "right", "both"} and "counts" in report
    assert "left  F1" in out
