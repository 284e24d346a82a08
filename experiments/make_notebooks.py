"""Writes the Colab notebooks in experiments/ (nbformat 4, no outputs). Edit the cells here, then run
`.venv/bin/python experiments/make_notebooks.py`; tests/test_notebooks.py runs every notebook in its tiny mode.

Conventions: a markdown cell first, then a setup cell that works on Colab and locally and defines TINY (the CI's
tiny configuration: DEXGUITAR_NOTEBOOK_TINY=1); commands run through `dexguitar.cli.main`, never a shell; no IPython
magics, so the code cells joined are a plain Python program."""
import json
from pathlib import Path

HERE = Path(__file__).resolve().parent

SETUP = '''\
# Setup. On Colab: fetch the code, install it with the CUDA build of JAX and an offscreen OpenGL for the video.
# Locally: work from the repository root (the setup of `make setup` is assumed).
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO_URL = "https://github.com/dexguitar/dexguitar"   # placeholder: point it at where the repository lives
if "google.colab" in sys.modules:
    if not Path("/content/dexguitar/pyproject.toml").exists():
        subprocess.run(["git", "clone", "--depth", "1", REPO_URL, "/content/dexguitar"], check=True)
    os.chdir("/content/dexguitar")
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "-e", ".[video,plot]",
                    "jax[cuda12]>=0.10.2,<0.12"], check=True)
    subprocess.run(["apt-get", "update", "-qq"], check=True)
    subprocess.run(["apt-get", "install", "-y", "-qq", "libosmesa6"], check=True)
else:
    root = Path.cwd().resolve()
    while not (root / "pyproject.toml").exists():
        if root.parent == root:
            raise SystemExit("start this notebook inside the dexguitar repository")
        root = root.parent
    os.chdir(root)
sys.path.insert(0, os.getcwd())

# TINY: the CI's configuration (tests/test_notebooks.py): the CPU config, 1-2 iterations, a 3-note song, outputs in
# a temporary folder. Everything else runs exactly as below.
TINY = os.environ.get("DEXGUITAR_NOTEBOOK_TINY") == "1"
WORK = Path(os.environ.get("DEXGUITAR_NOTEBOOK_OUT") or tempfile.mkdtemp(prefix="dexguitar-")) if TINY else Path(".")
TINY_SONG = WORK / "tiny.txt"
if TINY:
    WORK.mkdir(parents=True, exist_ok=True)
    TINY_SONG.write_text("title: two notes and a chord\\ntempo: 120\\ngrid: 1/8\\n"
                         "e|--0---------|\\nB|----1-------|\\nG|------0-----|\\n"
                         "D|------2-----|\\nA|------3-----|\\nE|------------|\\n")

# dexguitar([...]) is the `dexguitar ...` command
from dexguitar.cli import main as dexguitar

try:
    from IPython.display import {display_names}
except ImportError:                            # plain Python (the CI): print what would be shown
    display = print
{fallbacks}
print("TINY" if TINY else "full", "run in", os.getcwd())
'''

FALLBACKS = {
    "Image": "    def Image(filename): return f\"[image {filename}]\"",
    "Video": "    def Video(filename, **kw): return f\"[video {filename}]\"",
    "Audio": "    def Audio(filename, **kw): return f\"[audio {filename}]\"",
}


def setup(*names: str) -> str:
    return SETUP.replace("{display_names}", ", ".join(sorted(names) + ["display"])).replace(
        "{fallbacks}", "\n".join(FALLBACKS[n] for n in sorted(names)))


TRAIN = [
    ("md", '''\
# Train one hand

Trains the **left hand** on *Ode to Joy* with PPO plus motion imitation (the config `left_gpu`: 4,096 envs),
for 8 minutes of wall time, then evaluates it by the paper's per-note F1 and plots F1 against the samples seen.

Wants a **GPU runtime** on Colab (*Runtime → Change runtime type*): about 15 minutes in all (setup 2–3 min,
compilation 1–3 min, training 8 min, evaluation under a minute). The shipped `models/policies/left_ode_to_joy`
reached F1 1.000 in 6.5 minutes on an H200; a smaller GPU gets fewer samples in the 8 minutes (if it runs out of
memory, add `"--envs", "2048"`).

**After a Colab disconnect**: the run saves a checkpoint after every call, so re-run the setup cell and the training
cell with `RESUME = True` (the `--resume` flag): it continues `runs/left` from its last checkpoint. A disconnect that
recycles the machine loses `/content`; to survive that, put `RUN` on a mounted Google Drive.'''),
    ("code", setup("Image")),
    ("md", '''\
## Train

`dexguitar train --hand left --song ode_to_joy --config left_gpu --out runs/left --max-minutes 8`.
Progress goes to stderr (samples/s, F1, reward); `runs/left/metrics.jsonl` gets a line per call, `runs/left/policy/`
the exported policy.'''),
    ("code", '''\
RUN = str(WORK / "runs" / "left")
RESUME = False           # True: continue RUN from its last checkpoint (after a disconnect, or to train longer)
CONFIG = "cpu_smoke" if TINY else "left_gpu"      # dexguitar/configs/

args = ["train", "--hand", "left", "--song", "ode_to_joy", "--config", CONFIG, "--out", RUN, "--max-minutes", "8"]
if TINY:
    args += ["--iterations", "1"]
if RESUME:
    args += ["--resume"]
assert dexguitar(args) == 0'''),
    ("md", '''\
## Evaluate

F1 per hand by the paper's rules (Sec. 6.1): a fretted note counts when the target fret is pressed for at least 2/3
of the note. `--json` prints the same as JSON, `--notes` adds the per-note rows.'''),
    ("code", '''\
EVAL_SONG = str(TINY_SONG) if TINY else "ode_to_joy"
assert dexguitar(["eval", "--ckpt", RUN, "--song", EVAL_SONG]) == 0'''),
    ("md", '''\
## F1 against samples

From `metrics.jsonl` (the F1 of the training episodes, measured as they finish).'''),
    ("code", '''\
F1_PNG = str(WORK / "f1.png")
assert dexguitar(["plot", RUN, "--out", F1_PNG]) == 0
display(Image(filename=F1_PNG))'''),
]

SYNC = [
    ("md", '''\
# Synchronize the two hands

Two frozen policies — the left hand trained on *Strumming G - C - D* (`models/policies/left_strum_g_c_d`) and the
right hand trained on procedural picking and strumming patterns (`models/policies/right_patterns`) — are played
together in the duet env, and a small synchronizer (Sec. 4 of the paper) learns to shift their latents so that the
left hand presses before the right hand picks. The config `sync_gpu`: 4,096 duet envs.

Wants a **GPU runtime** on Colab (*Runtime → Change runtime type*): about 10 minutes in all (setup 2–3 min,
compilation 1–3 min, training 5 min, evaluation before and after synchronization about a minute). After a
disconnect, re-run with `"--resume"` added to the `sync` command: it continues `runs/sync-strum` from its last
checkpoint (`--left`/`--right` are then taken from the run).'''),
    ("code", setup()),
    ("md", '''\
## Train the synchronizer

`dexguitar sync --song strum_g_c_d --left models/policies/left_strum_g_c_d --right models/policies/right_patterns
--config sync_gpu --out runs/sync-strum --max-minutes 5`. When training stops it evaluates the pair
before and after synchronization on the song and writes `runs/sync-strum/eval.json`.'''),
    ("code", '''\
LEFT, RIGHT = "models/policies/left_strum_g_c_d", "models/policies/right_patterns"
SONG = str(TINY_SONG) if TINY else "strum_g_c_d"
RUN = str(WORK / "runs" / "sync-strum")
CONFIG = "cpu_smoke" if TINY else "sync_gpu"      # dexguitar/configs/

args = ["sync", "--song", SONG, "--left", LEFT, "--right", RIGHT, "--config", CONFIG, "--out", RUN,
        "--max-minutes", "5"]
if TINY:
    args += ["--iterations", "1", "--no-eval"]    # the CI evaluates once, below
assert dexguitar(args) == 0'''),
    ("md", '''\
## F1 before and after synchronization

From `eval.json`: per song and hand (`left`: pressed right; `right`: picked right; `both`: picked right while the
left hand holds the press, the duet's strict rule).'''),
    ("code", '''\
import json


def f1_table(staged):
    """staged: {"before": {song: summary}, "after": {song: summary}} as in eval.json."""
    print(f"{'song':32s} {'hand':5s} {'before':>7s} {'after':>7s} {'change':>7s}  notes")
    for title, before in staged["before"].items():
        after = staged["after"][title]
        for hand in ("left", "right", "both"):
            b, a = before[hand]["f1"], after[hand]["f1"]
            print(f"{title[:32]:32s} {hand:5s} {b:7.3f} {a:7.3f} {a - b:+7.3f}  {after[hand]['notes']}")


EVAL_JSON = Path(RUN) / "eval.json"
if EVAL_JSON.exists():
    f1_table(json.loads(EVAL_JSON.read_text()))
else:
    print(f"no {EVAL_JSON} (the sync ran with --no-eval): see the evaluation below")'''),
    ("md", '''\
## Evaluate the synchronizer

`dexguitar eval --ckpt runs/sync-strum --song strum_g_c_d`: a synchronizer is evaluated before and after
synchronization (any song, e.g. a held-out one; `--json` for machine-readable output, which `f1_table` above
formats). To watch and hear the synchronized pair, use `play_and_listen.ipynb` with `SYNC = "runs/sync-strum"`.'''),
    ("code", '''\
assert dexguitar(["eval", "--ckpt", RUN, "--song", SONG]) == 0'''),
]

PLAY = [
    ("md", '''\
# Play and listen

Both hands play the first 20 s of *Ode to Joy* with the shipped policies (`models/policies/left_ode_to_joy` and
`models/policies/right_patterns`, no synchronizer), then the notebook shows the video, plays the synthesized audio
and prints the per-note report (F1 per hand; each note right, late or wrong, with the reason). Set `SYNC` to a
`dexguitar sync` run (e.g. `runs/sync-strum` from `synchronize.ipynb`, with `SONG = "strum_g_c_d"`) to hear a
synchronized pair instead.

Runs on a CPU too (`make demo` is the same command); on Colab a **GPU runtime** makes the rollout
faster, the video is rendered on the CPU either way: about 3–4 minutes in all with the setup.'''),
    ("code", setup("Audio", "Image", "Video")),
    ("md", '''\
## Play

`dexguitar play --left models/policies/left_ode_to_joy --right models/policies/right_patterns --song ode_to_joy
--seconds 20 --out out/demo` (or `--ckpt runs/sync-strum` for a synchronized pair): writes `out/demo.mp4` (picture
and sound; a PNG contact sheet when no video encoder is installed), `out/demo.wav` and `out/demo-report.json`.'''),
    ("code", '''\
LEFT, RIGHT = "models/policies/left_ode_to_joy", "models/policies/right_patterns"
SYNC = None              # e.g. "runs/sync-strum": a synchronizer (both hands) instead of LEFT and RIGHT
SONG, SECONDS, OUT = "ode_to_joy", 20, str(WORK / "out" / "demo")
if TINY:
    SONG, SECONDS = str(TINY_SONG), 1

players = ["--ckpt", SYNC] if SYNC else ["--left", LEFT, "--right", RIGHT]
args = ["play", *players, "--song", SONG, "--seconds", str(SECONDS), "--out", OUT]
if TINY:
    args += ["--size", "320x180"]
assert dexguitar(args) == 0'''),
    ("md", '''\
## Watch and listen'''),
    ("code", '''\
import json

report = json.loads(Path(OUT + "-report.json").read_text())
files = report["files"]
if "video" in files:
    display(Video(files["video"], embed=True, width=640))
elif "frames" in files:                # no video encoder: a contact sheet of frames
    display(Image(filename=files["frames"]))
else:                                  # no offscreen OpenGL: sound and report only
    print("no picture: this machine has no offscreen OpenGL (apt-get install libosmesa6)")
display(Audio(filename=files["audio"]))'''),
    ("md", '''\
## The per-note report

`counts`: notes judged right, late (sounded, but picked after the first third of the note) and wrong; `summary`: F1,
precision and recall per hand (`both`: picked right while the left hand holds the press).'''),
    ("code", '''\
print(report["title"], f"({report['seconds']:.1f} s):",
      ", ".join(f"{k} {v}" for k, v in report["counts"].items()))
for hand in ("left", "right", "both"):
    s = report["summary"][hand]
    if s["f1"] is None:                      # no note concerned this hand (the report's JSON has no NaN)
        print(f"  {hand:5s} F1 undefined ({s['notes']} notes)")
        continue
    print(f"  {hand:5s} F1 {s['f1']:.3f}  P {s['precision']:.3f}  R {s['recall']:.3f}  ({s['notes']} notes)")
wrong = [r for r in report["notes"] if r["verdict"] in ("wrong", "late") and r["note"] >= 0]
for r in wrong[:10]:
    print(f"  note {r['note']:3d}: {r['verdict']} {r['why']}")'''),
]


def notebook(cells, name: str) -> dict:
    out = []
    for i, (kind, text) in enumerate(cells):
        lines = text.splitlines(keepends=True)
        cell = {"cell_type": "markdown" if kind == "md" else "code", "id": f"{name}-{i}", "metadata": {},
                "source": lines}
        if kind == "code":
            cell.update(execution_count=None, outputs=[])
        out.append(cell)
    return {"cells": out, "nbformat": 4, "nbformat_minor": 5,
            "metadata": {"accelerator": "GPU", "colab": {"provenance": [], "gpuType": "T4"},
                         "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
                         "language_info": {"name": "python"}}}


if __name__ == "__main__":
    for name, cells in (("train_a_hand", TRAIN), ("synchronize", SYNC), ("play_and_listen", PLAY)):
        path = HERE / f"{name}.ipynb"
        path.write_text(json.dumps(notebook(cells, name), indent=1, ensure_ascii=False) + "\n")
        print("wrote", path)
