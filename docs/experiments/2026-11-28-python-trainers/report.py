"""Tables (Markdown, printed and written to tables.md) and the figure
(curve.png) of the runs given: their training curves by windows of
captor steps, their held-out capture rates with 95% Wilson intervals,
and for each seed the paired difference of the two trainers on the same
starts (95% normal interval of the mean paired difference).

    python report.py runs/sb3-captors-s0 runs/sb3-captors-s1 runs/py-ppo-s0 runs/py-ppo-s1 --out DIR
"""

import argparse
import csv
import math
from pathlib import Path

WINDOW = 200_000  # captor steps


def label(run: Path) -> tuple[str, str]:
    trainer = "SB3 PPO (SuperSuit, flat)" if "sb3" in run.name else "project example (t2e.vector_env)"
    return trainer, run.name.rsplit("-s", 1)[1]


def curve(run: Path) -> list[tuple[int, int, int, float]]:
    """(window end in captor steps, episodes, captures, wall-clock s)."""
    rows = list(csv.DictReader(open(run / "curve.csv")))
    out, per_env = [], None
    for r in rows:
        if "captor_steps" in r:
            steps, ended, caught = int(r["captor_steps"]), int(r["episodes"]), int(r["captured"])
        else:  # ppo_captors: env steps, and the capture rate of the iteration's episodes
            steps, ended = 3 * int(r["env_steps"]), int(r["episodes"])
            caught = round(float(r["capture_rate"]) * ended) if ended else 0
        end = min(math.ceil(steps / WINDOW) * WINDOW, 1_000_000)
        if not out or out[-1][0] != end:
            out.append([end, 0, 0, 0.0])
        out[-1][1] += ended
        out[-1][2] += caught
        out[-1][3] = float(r["seconds"])
    return [tuple(x) for x in out]


def wilson(k: int, n: int) -> tuple[float, float]:
    z, p = 1.96, k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return 100 * (centre - half), 100 * (centre + half)


def episodes(run: Path) -> dict:
    out = {}
    for r in csv.DictReader(open(run / "episodes.csv")):
        out[(r["maps"], r["class"], int(r["seed"]))] = (int(r["captured"]), int(r["steps"]))
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    cli = parser.parse_args()
    lines = []

    lines.append("Training episodes (200 steps, sampled actions, the training maps), captured % by window of captor steps; wall-clock at the window's end:\n")
    ends = sorted({e for run in cli.runs for e, *_ in curve(run)})
    lines.append("| trainer | seed | " + " | ".join(f"≤ {e // 1000} k" for e in ends) + " |")
    lines.append("|---|---|" + "---|" * len(ends))
    for run in cli.runs:
        trainer, seed = label(run)
        cells = {e: f"{100 * c / n:.1f} ({s:.0f} s)" if n else "–" for e, n, c, s in curve(run)}
        lines.append(f"| {trainer} | {seed} | " + " | ".join(cells.get(e, "–") for e in ends) + " |")

    lines.append("\nGreedy test episodes (500 steps, the same seeds for every run), captured % [95% Wilson], mean episode length:\n")
    played = {run: episodes(run) for run in cli.runs}
    classes = sorted({(m, c) for eps in played.values() for m, c, _ in eps}, key=lambda mc: (mc[0] != "test", ["small", "medium", "large"].index(mc[1]) if mc[1] in ("small", "medium", "large") else 9))
    lines.append("| trainer | seed | " + " | ".join(f"{m}: {c}" for m, c in classes) + " |")
    lines.append("|---|---|" + "---|" * len(classes))
    for run in cli.runs:
        trainer, seed = label(run)
        cells = []
        for m, c in classes:
            rows = [v for (mm, cc, _), v in played[run].items() if (mm, cc) == (m, c)]
            k, n = sum(x for x, _ in rows), len(rows)
            lo, hi = wilson(k, n)
            cells.append(f"{100 * k / n:.1f} [{lo:.1f}, {hi:.1f}], {sum(s for _, s in rows) / n:.0f} steps")
        lines.append(f"| {trainer} | {seed} | " + " | ".join(cells) + " |")

    sb3 = [r for r in cli.runs if "sb3" in r.name]
    ours = [r for r in cli.runs if "sb3" not in r.name]
    if sb3 and ours:
        lines.append("\nPaired difference, SB3 minus the project's example, same seed index, same starts: points of captured % [95% interval]:\n")
        lines.append("| seed | " + " | ".join(f"{m}: {c}" for m, c in classes) + " |")
        lines.append("|---|" + "---|" * len(classes))
        for a, b in zip(sb3, ours):
            cells = []
            for m, c in classes:
                keys = [k for k in played[a] if k[:2] == (m, c) and k in played[b]]
                d = [played[a][k][0] - played[b][k][0] for k in keys]
                n = len(d)
                mean = sum(d) / n
                sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1)) if n > 1 else 0.0
                half = 1.96 * sd / math.sqrt(n)
                cells.append(f"{100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}]")
            lines.append(f"| {label(a)[1]} | " + " | ".join(cells) + " |")

    text = "\n".join(lines) + "\n"
    print(text)
    title = "# Stable-Baselines3 and the project's example: the tables report.py writes\n\n"
    (cli.out / "tables.md").write_text(title + text)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    for run in cli.runs:
        trainer, seed = label(run)
        points = curve(run)
        left.plot([e / 1e6 for e, *_ in points], [100 * c / n for _, n, c, _ in points], marker="o",
                  color="tab:blue" if "sb3" in run.name else "tab:orange", linestyle="-" if seed == "0" else "--",
                  label=f"{trainer}, seed {seed}")
    left.set_xlabel("captor steps (millions)")
    left.set_ylabel("training episodes captured (%)")
    left.set_title("Training (200-step episodes, training maps)")
    left.set_ylim(0, 100)
    left.legend(fontsize=7)
    width = 0.8 / len(cli.runs)
    for i, run in enumerate(cli.runs):
        trainer, seed = label(run)
        ys, errs = [], [[], []]
        for m, c in classes:
            rows = [v for (mm, cc, _), v in played[run].items() if (mm, cc) == (m, c)]
            k, n = sum(x for x, _ in rows), len(rows)
            lo, hi = wilson(k, n)
            ys.append(100 * k / n)
            errs[0].append(100 * k / n - lo)
            errs[1].append(hi - 100 * k / n)
        right.bar([j + i * width for j in range(len(classes))], ys, width, yerr=errs, capsize=2,
                  color="tab:blue" if "sb3" in run.name else "tab:orange", alpha=1.0 if seed == "0" else 0.6,
                  label=f"{trainer}, seed {seed}")
    right.set_xticks([j + 0.4 - width / 2 for j in range(len(classes))], [f"{m}\n{c}" for m, c in classes])
    right.set_ylabel("greedy test episodes captured (%)")
    right.set_title("Test (500 steps, same starts; 95% Wilson)")
    right.set_ylim(0, 105)
    fig.suptitle("Captors against the rule-based target, 1 M captor steps, 2-core CPU machine, one thread per run")
    fig.tight_layout()
    fig.savefig(cli.out / "curve.png", dpi=90)


if __name__ == "__main__":
    main()
