"""The Colab notebooks in experiments/ run top to bottom: each one's code cells, joined, run in the test's process as a
kernel would run them, in their tiny configuration (DEXGUITAR_NOTEBOOK_TINY=1: the CPU config, 1 iteration, a 3-note
song), with the suite's compilation cache (tests/conftest.py). They are written by experiments/make_notebooks.py."""
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = ROOT / "experiments"
NAMES = ("train_a_hand", "synchronize", "play_and_listen")


def cells(name: str, kind: str = "code") -> list[str]:
    nb = json.loads((NOTEBOOKS / f"{name}.ipynb").read_text())
    assert nb["nbformat"] == 4
    return ["".join(c["source"]) if isinstance(c["source"], list) else c["source"]
            for c in nb["cells"] if c["cell_type"] == kind]


@pytest.fixture
def run_notebook(monkeypatch, capsys):
    """run_notebook(name, out) -> what the notebook printed. A failing cell fails the test with its traceback."""
    def run(name: str, out: Path) -> str:
        monkeypatch.setenv("DEXGUITAR_NOTEBOOK_TINY", "1")
        monkeypatch.setenv("DEXGUITAR_NOTEBOOK_OUT", str(out))
        monkeypatch.chdir(ROOT)
        monkeypatch.setattr(sys, "path", list(sys.path))           # the setup cell puts the repository first
        capsys.readouterr()
        exec(compile("\n\n".join(cells(name)), f"{name}.ipynb", "exec"), {"__name__": "__main__"})
        return capsys.readouterr().out
    return run


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


def test_train_a_hand(tmp_path, run_notebook):
    out = run_notebook("train_a_hand", tmp_path)
    run = tmp_path / "runs" / "left"
    assert len((run / "metrics.jsonl").read_text().splitlines()) == 1
    assert json.loads((run / "policy" / "policy.json").read_text())["hand"] == "left"
    assert "two notes and a chord: left F1" in out               # the evaluation
    assert (tmp_path / "f1.png").stat().st_size > 0


def test_synchronize(tmp_path, run_notebook):
    out = run_notebook("synchronize", tmp_path)
    run = tmp_path / "runs" / "sync-strum"
    assert json.loads((run / "policy" / "policy.json").read_text())["kind"] == "synchronizer"
    assert len((run / "metrics.jsonl").read_text().splitlines()) == 1
    assert "[before synchronization] two notes and a chord" in out
    assert "[after synchronization] two notes and a chord" in out


def test_play_and_listen(tmp_path, offscreen_gl, run_notebook):
    out = run_notebook("play_and_listen", tmp_path)
    prefix = tmp_path / "out" / "demo"
    assert prefix.with_suffix(".wav").stat().st_size > 44
    assert prefix.with_suffix(".mp4").exists() or prefix.with_suffix(".png").exists()
    report = json.loads(Path(str(prefix) + "-report.json").read_text())
    assert set(report["summary"]) >= {"left", "right", "both"} and "counts" in report
    assert "left  F1" in out
