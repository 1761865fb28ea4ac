"""Both captor teams against each target on the same starts: per target
and speed ratio, each team's capture rate (SR, 95% Wilson) and mean Time
(steps; an escape counts 500), and the mean paired difference of captures
(the team trained against the robust target minus the one trained against
the rule-based target) with its 95% normal interval. Then, per team and
speed ratio, the robust target minus the rule-based target on the same
starts. Prints two Markdown tables.

    python paired.py OUT
OUT: what run.sh wrote.
"""

import csv
import math
import sys
from pathlib import Path

TARGETS = [
    ("rule", "rule-based (team R trained against it)"),
    ("robust", "robust (team B trained against it)"),
    ("robust-other", "robust, other models (neither met it)"),
    ("tuned-best", "best hand-made (neither met it)"),
]


def wilson(k: int, n: int) -> tuple[float, float]:
    z = 1.959964
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return 100 * (centre - half), 100 * (centre + half)


def episodes(folder: Path) -> list[dict]:
    # A setting played again by a newer build is a second folder (the code
    # version is part of its name); its episodes must be the same.
    runs = sorted(x for x in folder.iterdir() if (x / "episodes.csv").exists())
    played = [list(csv.DictReader(open(d / "episodes.csv"))) for d in runs]
    assert played and all(p == played[0] for p in played), folder
    return played[0]


def cell(eps: list[dict]) -> str:
    caught = sum(e["captured"] == "true" for e in eps)
    n = len(eps)
    low, high = wilson(caught, n)
    time = sum(float(e["steps"]) for e in eps) / n
    return f"{100 * caught / n:.1f} [{low:.1f}, {high:.1f}] | {time:.0f}"


def paired(a: list[dict], b: list[dict]) -> str:
    """b minus a in captures, points, with the 95% normal interval."""
    assert [(e["seed"], e["map"]) for e in a] == [(e["seed"], e["map"]) for e in b]
    d = [int(y["captured"] == "true") - int(x["captured"] == "true") for x, y in zip(a, b)]
    n = len(d)
    m = sum(d) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in d) / (n - 1))
    h = 1.959964 * sd / math.sqrt(n)
    return f"{100 * m:+.1f} [{100 * (m - h):+.1f}, {100 * (m + h):+.1f}]"


def main(out: Path) -> None:
    print("| v_p:v_e | target | episodes | team R: SR % [95%] | Time | team B: SR % [95%] | Time | B minus R, points [95%] |")
    print("|---|---|---|---|---|---|---|---|")
    for ratio in ["1.2", "1.0"]:
        for name, label in TARGETS:
            r_dir, b_dir = out / f"rule-vs-{name}-{ratio}", out / f"robust-vs-{name}-{ratio}"
            if not (r_dir.exists() and b_dir.exists()):
                continue
            r, b = episodes(r_dir), episodes(b_dir)
            print(f"| 1.0:{ratio} | {label} | {len(r)} | {cell(r)} | {cell(b)} | {paired(r, b)} |")
    print()
    print("| captors | v_p:v_e | robust minus rule-based target, points [95%] |")
    print("|---|---|---|")
    for team, label in [("rule", "team R"), ("robust", "team B")]:
        for ratio in ["1.2", "1.0"]:
            rule = episodes(out / f"{team}-vs-rule-{ratio}")
            robust = episodes(out / f"{team}-vs-robust-{ratio}")
            print(f"| {label} | 1.0:{ratio} | {paired(rule, robust)} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
