"""From tabs to a synchronized pair and a table of F1, in one resumable command (`dexguitar songs`).

Stages, per group of songs (all the songs together by default, or each song alone with `per_song`):

  left    a left-hand policy trained on the group's songs as written (no fret shift, no tempo change: the authors'
          song-specific recipe, reference §3.4), warm-started from `left_init` (default: the shipped left hand of the
          15 official songs; None: from scratch, best with `experiments/left_songs.py` as its config)
  right   the general right hand (`right_mixed`) trained further on the group's picking, as written
  sync    a synchronizer of the two on the group's songs (paper Sec. 4)
  eval    every song of the group by the paper's rules: each hand alone, both before and after synchronization

Each stage is a run directory under `<out>/<group>/`; a stage that was interrupted resumes from its checkpoint with
the minutes it has left, and a finished one is skipped (`stages.json`). One row per song goes to `<out>/songs.json`
and `<out>/songs.md`. A stage can stop early once its training F1 (on the songs themselves, since nothing is
augmented) has reached `stop_f1` over the last three host calls.
"""
from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path

from dexguitar.errors import UserError
from dexguitar.learn import policy as PO
from dexguitar.learn.run import load_config, train
from dexguitar.learn.sync import SyncTrainer
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import load_song
from dexguitar.music import timeline as TL
from dexguitar.perform.evaluate import evaluate, evaluate_synchronizer

ROOT = Path(__file__).resolve().parents[2]
STAGES = ("left", "right", "sync")


@dataclasses.dataclass(frozen=True)
class Recipe:
    """How each stage trains. Minutes are wall time on the device, compilation included."""

    left_config: str = str(ROOT / "experiments" / "left_finetune.py")
    right_config: str = str(ROOT / "experiments" / "right_songs.py")
    sync_config: str = str(ROOT / "experiments" / "sync_songs.py")
    left_init: str | None = str(ROOT / "models" / "policies" / "left_official15")
    right_init: str = str(ROOT / "models" / "policies" / "right_mixed")
    left_minutes: float = 3.0
    right_minutes: float = 2.0
    sync_minutes: float = 5.0
    stop_f1: float | None = None       # stop a stage once its training F1 reaches this (None: use the minutes)
    iterations: int | None = None      # cap every stage's iterations (tests)
    envs: int | None = None            # override every config's num_envs


def song_name(path) -> str:
    return Path(str(path)).stem


def _spent(run: Path) -> float:
    """Minutes a stage has trained so far: its host calls plus the compilation of each process."""
    rows = [json.loads(r) for r in (run / "metrics.jsonl").read_text().splitlines() if r.strip()] if (
        run / "metrics.jsonl").exists() else []
    compiles = {r.get("compile_s", 0.0) for r in rows}
    return (sum(r.get("seconds", 0.0) for r in rows) + sum(compiles)) / 60.0


class Songbook:
    """The stages of one group of songs in `<out>/<group>/`."""

    def __init__(self, out, group: str, paths, recipe: Recipe, log=None):
        self.dir = Path(out) / group
        self.group, self.recipe = group, recipe
        self.paths = [str(p) for p in paths]
        self.songs = [load_song(p) for p in paths]
        self.log = log or (lambda msg: print(msg, file=sys.stderr))
        self.dir.mkdir(parents=True, exist_ok=True)
        self.state_file = self.dir / "stages.json"
        self.state = json.loads(self.state_file.read_text()) if self.state_file.exists() else {}
        if self.state.get("songs", self.paths) != self.paths:
            raise UserError(f"{self.dir} holds stages for other songs ({', '.join(self.state['songs'])}); "
                            f"choose another --out")
        self.state["songs"] = self.paths

    def _save(self):
        tmp = self.state_file.with_suffix(".tmp")
        tmp.write_text(json.dumps(self.state, indent=2))
        tmp.replace(self.state_file)

    def run(self, stage: str) -> None:
        if stage in self.state.get("done", {}):
            self.log(f"[{self.group}] {stage}: done before ({self.state['done'][stage]['minutes']:.1f} min)")
            return
        r = self.recipe
        minutes = {"left": r.left_minutes, "right": r.right_minutes, "sync": r.sync_minutes}[stage]
        run_dir = self.dir / stage
        spent = _spent(run_dir)
        left = max(minutes - spent, 0.0)
        self.log(f"[{self.group}] {stage}: training for {left:.1f} of {minutes:.1f} min on "
                 f"{len(self.songs)} song(s)")
        timelines = [TL.from_song(s) for s in self.songs]
        hand = "left" if stage == "left" else "right"
        config = {"left": r.left_config, "right": r.right_config, "sync": r.sync_config}[stage]
        cfg, env_cfg = load_config(config, hand="duet" if stage == "sync" else hand, num_envs=r.envs,
                                   iterations=r.iterations)
        resume = (run_dir / "config.json").exists()
        meta = {"songs": [s.title for s in self.songs]}
        if stage == "sync":
            pair = PO.load_pair(self.dir / "left", self.dir / "right")
            motion = load_motion("left")
            trainer = SyncTrainer(cfg, timelines, reference_frames(motion), *pair, env_cfg)
            meta.update(left=str(self.dir / "left"), right=str(self.dir / "right"))
        else:
            trainer = Trainer(cfg, timelines, reference_frames(load_motion(hand)), env_cfg)
        if left > 0:
            summary = train(trainer, run_dir, iterations=cfg.iterations, resume=resume, meta=meta,
                            max_minutes=left, init_from=None if resume else {"left": r.left_init,
                                                                             "right": r.right_init}.get(stage),
                            stop_f1=r.stop_f1, log=self.log)
            self.log(f"[{self.group}] {stage}: {summary.get('samples', 0):,} samples, training F1 "
                     + " ".join(f"{k[3:]} {v:.3f}" for k, v in summary.items() if k.startswith("f1/") and v == v))
        self.state.setdefault("done", {})[stage] = {"minutes": _spent(run_dir)}
        self._save()

    def evaluate(self) -> list[dict]:
        """One row per song: F1 of each hand alone, both before and after synchronization."""
        if "eval" in self.state:
            return self.state["eval"]
        left = PO.load(self.dir / "left")
        right = PO.load(self.dir / "right")
        sync = PO.load(self.dir / "sync")
        alone = {h: evaluate(p, PO.PolicySpec.from_meta(m), self.songs) for h, (p, m) in
                 (("left", left), ("right", right))}
        staged = evaluate_synchronizer(sync[0], PO.PolicySpec.from_meta(sync[1]), self.songs)
        minutes = sum(self.state["done"][s]["minutes"] for s in STAGES)
        rows = []
        for path, song, title in zip(self.paths, self.songs, alone["left"]):
            before, after = staged["before"][title]["summary"], staged["after"][title]["summary"]
            rows.append({"song": song_name(path), "left": alone["left"][title]["summary"]["left"]["f1"],
                         "right": alone["right"][title]["summary"]["right"]["f1"],
                         "both_before": before["both"]["f1"], "both_after": after["both"]["f1"],
                         "left_after": after["left"]["f1"], "right_after": after["right"]["f1"],
                         "gpu_minutes": round(minutes / len(self.songs), 2),
                         "trained_on": [song_name(p) for p in self.paths]})
            self.log(f"[{self.group}] {rows[-1]['song']}: left {rows[-1]['left']:.3f} right {rows[-1]['right']:.3f} "
                     f"both {rows[-1]['both_before']:.3f} -> {rows[-1]['both_after']:.3f}")
        self.state["eval"] = rows
        self._save()
        return rows


def run_songs(paths, out, recipe: Recipe = Recipe(), per_song: bool = False, log=None) -> list[dict]:
    """Every stage for every group, then the table; what is done already is skipped."""
    if not paths:
        raise UserError("songs: no tab files given")
    out = Path(out)
    groups = [(song_name(p), [p]) for p in paths] if per_song else [("all", list(paths))]
    rows = []
    t0 = time.perf_counter()
    for group, members in groups:
        book = Songbook(out, group, members, recipe, log)
        for stage in STAGES:
            book.run(stage)
        rows += book.evaluate()
        write_table(rows, out)
    (log or (lambda m: print(m, file=sys.stderr)))(f"songs: {len(rows)} rows in {out / 'songs.json'} "
                                                    f"({(time.perf_counter() - t0) / 60:.1f} min)")
    return rows


def write_table(rows: list[dict], out) -> None:
    out = Path(out)
    (out / "songs.json").write_text(json.dumps(rows, indent=1))
    lines = ["| song | left | right | both before | both after | left after | right after | GPU min | trained on |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| `{r['song']}` | {r['left']:.3f} | {r['right']:.3f} | {r['both_before']:.3f} | "
                     f"**{r['both_after']:.3f}** | {r['left_after']:.3f} | {r['right_after']:.3f} | "
                     f"{r['gpu_minutes']:.2f} | {len(r['trained_on'])} song(s) |")
    (out / "songs.md").write_text("\n".join(lines) + "\n")
