"""From tabs to a synchronized pair and a table of F1, in one resumable command (`dexguitar songs`).

Stages, per group of songs (all the songs together by default, or each song alone with `per_song`):

  left    a left-hand policy trained on the group's songs as written (no fret shift, no tempo change: the authors'
          song-specific recipe, reference §3.4), warm-started from `left_init` (default: the shipped left hand of the
          15 official songs; None: from scratch, best with the config `left_songs`, or with `left_residual` a
          residual on the IK planner)
  right   the general right hand (`right_mixed`) trained further on the group's picking, as written
  sync    a synchronizer of the two on the group's songs (paper Sec. 4)
  eval    every song of the group by the paper's rules: each hand alone, both before and after synchronization

Each stage is a run directory under `<out>/<group>/`; a stage that was interrupted resumes from its checkpoint with
the minutes it has left, and a finished one is skipped (`stages.json`). One row per song goes to `<out>/songs.json`
and `<out>/songs.md`.

A `Judge` plays the group's songs with each stage's export every half minute or so, by the paper's rules (the mean
action, whole songs), keeps the best export in `<stage>/best/` and ends the stage once that reaches the stage's
target. The training F1 cannot serve for this: it is measured with the exploration noise on (0.78 on a song that
the same synchronizer plays at 0.92 deterministically), and synchronization can raise it while the deterministic F1
falls. The unsynchronized pair is a candidate of the synchronization stage too, so synchronizing never leaves a pair
worse than it played alone.
"""
from __future__ import annotations

import dataclasses
import json
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from dexguitar.errors import UserError
from dexguitar.learn import policy as PO
from dexguitar.configs import load_config
from dexguitar.learn.run import train
from dexguitar.learn.sync import SyncTrainer
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import load_song
from dexguitar.music import timeline as TL
from dexguitar.perform.evaluate import dumps, evaluate, evaluate_synchronizer
from dexguitar.shipped import policies_dir

POLICIES = policies_dir()
STAGES = ("left", "right", "sync")


@dataclasses.dataclass(frozen=True)
class Recipe:
    """How each stage trains. Minutes are wall time on the device, compilation included."""

    left_config: str = "left_finetune"         # a name in dexguitar/configs/ or a .py file (`load_config`)
    right_config: str = "right_songs"
    sync_config: str = "sync_hold"
    left_set: tuple[str, ...] = ()             # KEY=VALUE overrides of each stage's config (`--set`)
    right_set: tuple[str, ...] = ()
    sync_set: tuple[str, ...] = ()
    left_init: str | None = str(POLICIES / "left_official15")
    right_init: str = str(POLICIES / "right_mixed")
    left_minutes: float = 3.0
    right_minutes: float = 2.0
    sync_minutes: float = 5.0
    left_target: float = 0.98          # end a stage once its best export plays this F1 (its hand; "both" for sync)
    right_target: float = 0.98
    sync_target: float = 0.97
    judge_seconds: float = 30.0        # training time between two judgements
    iterations: int | None = None      # cap every stage's iterations (tests)
    envs: int | None = None            # override every config's num_envs

    def start(self, stage: str) -> str | None:
        """The policy a hand stage starts from (a synchronizer starts from its stages' best exports)."""
        return {"left": self.left_init, "right": self.right_init}.get(stage)


def song_name(path) -> str:
    return Path(str(path)).stem


def _spent(run: Path) -> float:
    """Minutes a stage has spent so far: its host calls, the compilation of each process and its judgements."""
    rows = [json.loads(r) for r in (run / "metrics.jsonl").read_text().splitlines() if r.strip()] if (
        run / "metrics.jsonl").exists() else []
    compiles = {r.get("compile_s", 0.0) for r in rows}
    judged = json.loads((run / Judge.FILE).read_text())["seconds"] if (run / Judge.FILE).exists() else 0.0
    return (sum(r.get("seconds", 0.0) for r in rows) + sum(compiles) + judged) / 60.0


def _write_json(path: Path, obj) -> None:
    """Write `obj` to `path` whole or not at all (a kill mid-write leaves the previous file)."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(obj, indent=1))
    tmp.replace(path)


def best_export(run: Path) -> Path:
    """The export a stage hands on: its judged best, else its last."""
    return run / "best" if (run / "best" / "policy.json").exists() else PO.export_dir(run)


class Judge:
    """Deterministic whole-song F1 of a stage's export (the mean of its hand's F1 over the group's songs; "both" for a
    synchronizer), at most every `every_s` seconds. Keeps the best export in `<run>/best/` and its history in
    `judge.json`; returns True (stop) once the best reaches `target`."""

    FILE = "judge.json"

    def __init__(self, run: Path, songs, target: float, every_s: float, log, frozen_until: int = 0):
        self.run, self.songs, self.target, self.every_s, self.log = Path(run), songs, target, every_s, log
        self.frozen_until = frozen_until    # a synchronizer's actor has not moved yet: it is the pair alone
        path = self.run / self.FILE
        self.state = json.loads(path.read_text()) if path.exists() else {"best": None, "history": [],
                                                                         "seconds": 0.0}
        self.last = time.perf_counter()

    def score(self, params, meta: dict) -> float:
        spec = PO.PolicySpec.from_meta(meta)
        hand = "both" if spec.kind == "synchronizer" else spec.hand
        results = evaluate(params, spec, self.songs)
        return float(np.nanmean([r["summary"][hand]["f1"] for r in results.values()]))

    def __call__(self, iteration: int, force: bool = False) -> bool:
        done = [h["iteration"] for h in self.state["history"]]
        if (not force and time.perf_counter() - self.last < self.every_s) or iteration in done:
            return self.reached()
        if iteration <= self.frozen_until and done:                # the pair alone again, judged already
            return self.reached()
        t0 = time.perf_counter()
        params, meta = PO.load(self.run / "policy")
        candidates = [(iteration, params, meta)]
        if meta.get("kind") == "synchronizer" and not done:        # the pair as it plays alone
            candidates.insert(0, ("unsynchronized", PO.unsynchronized(params), dict(meta, unsynchronized=True)))
        if iteration <= self.frozen_until:                          # the synchronizer has not moved: that pair alone
            candidates = candidates[:1]
        for it, p, m in candidates:
            f1 = self.score(p, m)
            self.state["history"].append({"iteration": it, "f1": f1})
            if self.state["best"] is None or f1 > self.state["best"]["f1"]:
                tmp = self.run / "best.tmp"
                shutil.rmtree(tmp, ignore_errors=True)
                PO.export(tmp, p, m)
                shutil.rmtree(self.run / "best", ignore_errors=True)
                tmp.rename(self.run / "best")
                self.state["best"] = {"iteration": it, "f1": f1}
            self.log(f"  judged {self.run.name} at {it}: F1 {f1:.3f} (best {self.state['best']['f1']:.3f} at "
                     f"{self.state['best']['iteration']})")
        self.state["seconds"] += time.perf_counter() - t0
        _write_json(self.run / self.FILE, self.state)
        self.last = time.perf_counter()
        return self.reached()

    def reached(self) -> bool:
        return self.state["best"] is not None and self.state["best"]["f1"] >= self.target


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
        _write_json(self.state_file, self.state)

    def run(self, stage: str) -> None:
        if stage in self.state.get("done", {}):
            self.log(f"[{self.group}] {stage}: done before ({self.state['done'][stage]['minutes']:.1f} min)")
            return
        r = self.recipe
        minutes = {"left": r.left_minutes, "right": r.right_minutes, "sync": r.sync_minutes}[stage]
        target = {"left": r.left_target, "right": r.right_target, "sync": r.sync_target}[stage]
        run_dir = self.dir / stage
        if minutes <= 0 and stage != "sync":
            self._hand_on_start(stage, run_dir)
            return
        spent = _spent(run_dir)
        left = max(minutes - spent, 0.0)
        self.log(f"[{self.group}] {stage}: training for {left:.1f} of {minutes:.1f} min on "
                 f"{len(self.songs)} song(s)")
        timelines = [TL.from_song(s) for s in self.songs]
        hand = "left" if stage == "left" else "right"
        config = {"left": r.left_config, "right": r.right_config, "sync": r.sync_config}[stage]
        sets = {"left": r.left_set, "right": r.right_set, "sync": r.sync_set}[stage]
        cfg, env_cfg = load_config(config, sets, hand="duet" if stage == "sync" else hand, num_envs=r.envs,
                                   iterations=r.iterations)
        resume = (run_dir / "config.json").exists()
        meta = {"songs": [s.title for s in self.songs]}
        if stage == "sync":
            pair = PO.load_pair(best_export(self.dir / "left"), best_export(self.dir / "right"))
            motion = load_motion("left")
            trainer = SyncTrainer(cfg, timelines, reference_frames(motion), *pair, env_cfg)
            meta.update(left=str(self.dir / "left"), right=str(self.dir / "right"))
        else:
            trainer = Trainer(cfg, timelines, reference_frames(load_motion(hand)), env_cfg)
        judge = Judge(run_dir, self.songs, target, r.judge_seconds, self.log,
                      frozen_until=cfg.actor_warmup if stage == "sync" else 0)
        if left > 0 and not judge.reached():
            summary = train(trainer, run_dir, iterations=cfg.iterations, resume=resume, meta=meta,
                            max_minutes=left, init_from=None if resume else r.start(stage),
                            on_call=judge, log=self.log)
            if "iteration" in summary:              # the last export, if the judge has not seen it yet
                judge(summary["iteration"], force=True)
            self.log(f"[{self.group}] {stage}: {summary.get('samples', 0):,} samples, training F1 "
                     + " ".join(f"{k[3:]} {v:.3f}" for k, v in summary.items() if k.startswith("f1/") and v == v)
                     + (f"; best export F1 {judge.state['best']['f1']:.3f} at {judge.state['best']['iteration']}"
                        if judge.state["best"] else ""))
        self.state.setdefault("done", {})[stage] = {"minutes": _spent(run_dir)}
        self._save()

    def _hand_on_start(self, stage: str, run_dir: Path) -> None:
        """A hand stage of 0 minutes hands its starting policy on as it is (`right_mixed` already plays most
        songs' picking at 0.9-0.95; its one-minute stage mostly compiled and trained 25 iterations)."""
        start = self.recipe.start(stage)
        if start is None or not (Path(start) / "policy.json").exists():
            raise UserError(f"{stage} stage of 0 minutes: no policy to start from at {start}")
        shutil.rmtree(run_dir / "best", ignore_errors=True)
        shutil.copytree(start, run_dir / "best")
        self.log(f"[{self.group}] {stage}: 0 minutes, {start} as it is")
        self.state.setdefault("done", {})[stage] = {"minutes": 0.0}
        self._save()

    def evaluate(self) -> list[dict]:
        """One row per song: F1 of each hand alone, both before and after synchronization."""
        if "eval" in self.state:
            return self.state["eval"]
        left, right, sync = (PO.load(best_export(self.dir / s)) for s in STAGES)
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
                         "synchronized": not sync[1].get("unsynchronized", False),
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
    (log or (lambda m: print(m, file=sys.stderr)))(f"songs: {len(rows)} row{'s' * (len(rows) != 1)} in "
                                                    f"{out / 'songs.json'} ({(time.perf_counter() - t0) / 60:.1f} min)")
    return rows


def write_table(rows: list[dict], out) -> None:
    out = Path(out)
    (out / "songs.json").write_text(dumps(rows, indent=1))
    lines = ["| song | left | right | both before | both after | left after | right after | GPU min | trained on |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        alone = "" if r.get("synchronized", True) else " (alone)"        # the synchronizer was not kept
        lines.append(f"| `{r['song']}` | {r['left']:.3f} | {r['right']:.3f} | {r['both_before']:.3f} | "
                     f"**{r['both_after']:.3f}**{alone} | {r['left_after']:.3f} | {r['right_after']:.3f} | "
                     f"{r['gpu_minutes']:.2f} | {len(r['trained_on'])} song(s) |")
    (out / "songs.md").write_text("\n".join(lines) + "\n")
