"""The left-hand recipe sweep as a table: F1 on the training windows after 100, 200 and 300 iterations and the
whole song's F1 at the end, per variant (results/left_sweep/*/). Usage: python experiments/left_sweep/report.py"""
import dataclasses
import json
import runpy
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parents[1] / "results" / "left_sweep"
BASE = RESULTS.parent / "official_songs"


def rows(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def at(metrics: list[dict], iteration: int) -> str:
    hit = [m for m in metrics if m["iteration"] == iteration]
    return f"{hit[0]['f1/left']:.3f}" if hit else "–"


def main(out=sys.stdout) -> None:
    runs = {"baseline, turkish_march, alone": (BASE / "turkish_march/left/metrics.jsonl", None),
            "baseline, super_mario, alone": (BASE / "super_mario/left/metrics.jsonl", None)}
    table = {r["song"]: r for r in json.loads((RESULTS.parent / "official_songs.json").read_text())}
    for d in sorted(p for p in RESULTS.iterdir() if p.is_dir()):
        runs[d.name] = (d / "metrics.jsonl", d / "eval.json")
    out.write("| variant | changed | it 100 | it 200 | it 300 | song F1 at the end | iterations | samples (M) |\n")
    out.write("|---|---|---:|---:|---:|---:|---:|---:|\n")
    ref = dataclasses.asdict(runpy.run_path(str(Path(__file__).with_name("base.py")))["CONFIG"])
    for name, (metrics_path, eval_path) in runs.items():
        m = rows(metrics_path)
        song = "–"
        if eval_path is None:                 # a baseline: its song's row in the official table
            stem = name.split(", ")[1]
            song = f"{stem} {table[stem]['left']:.3f}"
        if eval_path is not None and eval_path.is_file():
            ev = json.loads(eval_path.read_text())
            song = "; ".join(f"{s} {v['left']['f1']:.3f}" for s, v in ev.items())
        changed = "–"
        cfg_path = metrics_path.parent / "config.json"
        if cfg_path.is_file() and eval_path is not None:
            cfg = json.loads(cfg_path.read_text())
            cfg = cfg.get("train", cfg)
            changed = ", ".join(f"{k}={cfg[k]}" for k in cfg if k in ref and cfg[k] != ref[k]) or "–"
        out.write(f"| {name} | {changed} | {at(m, 100)} | {at(m, 200)} | {at(m, 300)} | {song} | "
                  f"{m[-1]['iteration']} | {m[-1]['samples'] / 1e6:.1f} |\n")


if __name__ == "__main__":
    main()
