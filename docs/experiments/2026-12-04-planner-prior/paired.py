"""The planner-prior target against the rule-based and the robust targets
on the same starts: per speed ratio, each target's capture rate by one
test team (SR, 95% Wilson) and mean Time (steps; failures count 500), the
paired difference of captures (planner-prior minus the other, points,
95% normal interval), the share (%) of its decisions that departed from
the rule-based move, and the share of episodes it ends exactly as the
robust target does (the same outcome at the same step). Prints Markdown.

    python paired.py OUT [TEAM]   (run.sh's folder, beside TEAM-heuristic-R and TEAM-robust-R;
                                   TEAM greedy2 (the default), expert7 or mappo-sight)
"""

import csv
import json
import math
import sys
from pathlib import Path


def wilson(k: int, n: int) -> tuple[float, float]:
    z = 1.959964
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return 100 * (centre - half), 100 * (centre + half)


def setting(folder: Path):
    """The one setting folder of an eval output: its episodes and summary."""
    (dir,) = [d for d in folder.iterdir() if (d / "episodes.csv").exists()]
    return list(csv.DictReader(open(dir / "episodes.csv"))), json.load(open(dir / "summary.json"))


def paired(a, b) -> str:
    """b minus a, in points of SR, with its 95% interval."""
    d = [int(y["captured"] == "true") - int(x["captured"] == "true") for x, y in zip(a, b)]
    n = len(d)
    mean = sum(d) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1))
    half = 1.959964 * sd / math.sqrt(n)
    return f"{100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}]"


def main(out: Path, team: str) -> None:
    print("| v_p:v_e | learned target | target | episodes | SR % [95%] | Time | learned minus it, points [95%] | departures from the rule % | episodes ended as the robust target's % |")
    print("|---|---|---|---|---|---|---|---|---|")
    for variant in ["planner-prior", "planner-prior-w8", "planner-prior-w6", "planner-prior-w3"]:
        for ratio in ["1.0", "1.2"]:
            try:
                learned, learned_summary = setting(out / f"{team}-{variant}-{ratio}")
                # The learned target's episodes are the first of the others'.
                n = len(learned)
                others = {}
                for t in ["heuristic", "robust"]:
                    episodes, summary = setting(out / f"{team}-{t}-{ratio}")
                    # Its departures cover all its episodes: shown only when those are the n.
                    others[t] = (episodes[:n], summary if len(episodes) == n else {})
            except (FileNotFoundError, ValueError):
                continue  # a setting not played (yet)
            starts = [(e["seed"], e["map"]) for e in learned]
            for t, (episodes, _) in others.items():
                assert [(e["seed"], e["map"]) for e in episodes] == starts, f"{t} {ratio}: not the same starts"
            robust = others["robust"][0]
            same = sum((x["captured"], x["steps"]) == (y["captured"], y["steps"]) for x, y in zip(learned, robust))
            rows = [*others.items(), (variant, (learned, learned_summary))]
            for t, (episodes, summary) in rows:
                k = sum(e["captured"] == "true" for e in episodes)
                lo, hi = wilson(k, n)
                time = sum(int(e["steps"]) for e in episodes) / n
                diff = "–" if t == variant else paired(episodes, learned)
                dep = summary.get("target_departure")
                dep = "–" if dep is None else f"{dep:.2f}"
                agree = f"{100 * same / n:.1f}" if t == variant else "–"
                print(f"| 1.0:{ratio} | {variant} | {t} | {n} | {100 * k / n:.1f} [{lo:.1f}, {hi:.1f}] | {time:.0f} | {diff} | {dep} | {agree} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]), sys.argv[2] if len(sys.argv) > 2 else "greedy2")
