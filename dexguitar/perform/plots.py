"""Learning curves from `metrics.jsonl`: F1 per hand against env samples (matplotlib, the optional `plot` extra)."""
from __future__ import annotations

import json
from pathlib import Path


def read_metrics(run) -> list[dict]:
    path = Path(run) / "metrics.jsonl" if Path(run).is_dir() else Path(run)
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _hands(rows) -> tuple[str, ...]:
    """The hands a run trains, from its reward columns."""
    keys = rows[0].keys() if rows else ()
    left, right = "reward/string1" in keys, "reward/pick" in keys
    return ("left", "right", "both") if left and right else ("right",) if right else ("left",)


def plot_f1(runs, out, labels=None, title: str = "F1 per note during training") -> Path:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as err:
        raise SystemExit("plotting needs matplotlib: pip install -e '.[plot]'") from err
    fig, ax = plt.subplots(figsize=(7, 4))
    for i, run in enumerate(runs):
        rows = read_metrics(run)
        for hand in _hands(rows):
            pts = [(r["samples"], r[f"f1/{hand}"]) for r in rows if r.get(f"notes/{hand}", 0) > 0]
            if pts:
                name = labels[i] if labels else Path(run).name
                ax.plot([p[0] / 1e6 for p in pts], [p[1] for p in pts], label=f"{name}: {hand}")
    ax.set_xlabel("env samples (millions)")
    ax.set_ylabel("F1 (training windows)")
    ax.set_ylim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    return Path(out)
