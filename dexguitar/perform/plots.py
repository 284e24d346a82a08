"""Learning curves from `metrics.jsonl`: F1 per hand against env samples (matplotlib, the optional `plot` extra)."""
from __future__ import annotations

import json
from pathlib import Path

from dexguitar.errors import UserError


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
        raise UserError("plotting needs matplotlib: pip install -e '.[plot]'") from err
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
    if ax.get_legend_handles_labels()[0]:       # a run that has judged no note yet has no line
        ax.legend()
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    return Path(out)


F1_BINS = 10     # Fig. 5: ten bins of width 0.1 over [0, 1]
GOOD_F1 = 0.8    # the paper's "chords above 0.8" (about 40 % for its general left hand)
POOR_F1 = 0.5    # ... and "below 0.5" (about 20 %)
EDGE = 1e-9      # an F1 on a bin edge (0.3, computed as 0.29999999999999993) belongs to the bin above it


def chord_f1_histogram(chord_f1) -> list[float]:
    """Fraction of chords per F1 bin [0, 0.1), [0.1, 0.2), ..., [0.9, 1.0]; F1 = 1 falls in the last bin.

    chord_f1: {chord: f1} (`evaluate.summarize(...)["chords"]`, possibly merged over songs) or a list of F1s."""
    values = list(chord_f1.values()) if isinstance(chord_f1, dict) else list(chord_f1)
    if not values:
        raise ValueError("no chords to count")
    counts = [0] * F1_BINS
    for f1 in values:
        if not 0.0 <= f1 <= 1.0:
            raise ValueError(f"F1 {f1} outside [0, 1]")
        counts[min(int(f1 * F1_BINS + EDGE), F1_BINS - 1)] += 1
    return [c / len(values) for c in counts]


def plot_chord_histogram(chord_f1, out, title: str = "F1 of the left hand per chord") -> Path:
    """The paper's Fig. 5: the distribution of per-chord F1, annotated with the shares >= 0.8 and < 0.5."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as err:
        raise UserError("plotting needs matplotlib: pip install -e '.[plot]'") from err
    frac = chord_f1_histogram(chord_f1)
    good, poor = sum(frac[round(GOOD_F1 * F1_BINS):]), sum(frac[:round(POOR_F1 * F1_BINS)])
    n = len(chord_f1)
    fig, ax = plt.subplots(figsize=(6, 3.5))
    width = 1.0 / F1_BINS
    ax.bar([i * width for i in range(F1_BINS)], frac, width=width, align="edge", edgecolor="black")
    ax.set_xlim(0, 1)
    ax.set_xticks([i * width for i in range(F1_BINS + 1)])
    ax.set_xlabel("F1")
    ax.set_ylabel("fraction of chords")
    ax.text(0.35, 0.95, f"{n} chords\nF1 >= {GOOD_F1}: {good:.0%}\nF1 < {POOR_F1}: {poor:.0%}",
            transform=ax.transAxes, va="top")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return Path(out)


def chords_from_eval(paths) -> list[float]:
    """The per-chord F1s of `dexguitar eval --json` outputs (a synchronizer's: its "after" stage), each chord of
    each song once."""
    values = []
    for path in paths:
        try:
            results = json.loads(Path(path).read_text())
        except (OSError, json.JSONDecodeError) as err:
            raise UserError(f"{path}: not the output of `dexguitar eval --json` ({err})") from None
        results = results.get("after", results)
        for title, summary in results.items():
            summary = summary.get("summary", summary)
            if not isinstance(summary, dict) or "chords" not in summary:
                raise UserError(f"{path}: {title!r} has no per-chord F1 (expected `dexguitar eval --json` output)")
            values += list(summary["chords"].values())
    return values
