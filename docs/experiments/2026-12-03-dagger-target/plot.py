"""recall.png: for each DAgger target, the share of the teacher's
departures its greedy move follows, against env steps, on the new rollout
before each fit (teacher.csv, solid) and on the states fitted on
(dagger.csv, dashed); sums over windows of 10 iterations.

    python plot.py OUT
"""

import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def curve(path: Path, window: int = 10) -> tuple[list[float], list[float]]:
    rows = list(csv.DictReader(open(path)))
    xs, ys = [], []
    for i in range(0, len(rows) - window + 1, window):
        chunk = rows[i:i + window]
        departures = sum(int(r["teacher_departures"]) for r in chunk)
        xs.append(int(chunk[-1]["env_steps"]) / 1e6)
        ys.append(100 * sum(int(r["followed"]) for r in chunk) / max(departures, 1))
    return xs, ys


def main(out: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 4))
    for run, colour in zip(sorted(out.glob("dagger-*")), ["C0", "C1", "C2", "C3", "C4"]):
        for name, style in [("teacher.csv", "-"), ("dagger.csv", "--")]:
            if (run / name).exists():
                xs, ys = curve(run / name)
                label = f"{run.name}, {'new states' if name == 'teacher.csv' else 'fitted on'}"
                ax.plot(xs, ys, style, color=colour, label=label)
    ax.set_xlabel("env steps (M)")
    ax.set_ylabel("teacher's departures followed (%)")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(Path(__file__).parent / "recall.png", dpi=110)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
