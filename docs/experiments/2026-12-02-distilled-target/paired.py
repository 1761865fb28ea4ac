"""Every target beside the rule-based target on the same starts: per team
and speed ratio, each target's capture rate (SR, 95% Wilson) and mean Time
(steps; an escape counts 500), and the mean paired difference of captures
(the target minus the rule-based target) with its 95% normal interval.
Prints a Markdown table.

    python paired.py OUT SIGHT_OUT
OUT: what run.sh wrote; SIGHT_OUT: what ../2026-12-01-robust-target/sight.sh
wrote (the rule-based and robust rows against MAPPO with sight).
"""

import csv
import math
import sys
from pathlib import Path


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


def paired_difference(caught_rule: list[bool], caught: list[bool]) -> str:
    """The mean per-episode difference in capture, in points, with its 95% normal interval."""
    n = len(caught)
    d = [int(b) - int(a) for a, b in zip(caught_rule, caught)]
    m = sum(d) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in d) / (n - 1))
    h = 1.959964 * sd / math.sqrt(n)
    return f"{100 * m:+.1f} [{100 * (m - h):+.1f}, {100 * (m + h):+.1f}]"


def table_row(team: str, ratio: str, label: str, folder: Path, rule: list[dict], is_rule: bool) -> str:
    """One Markdown row: the episodes in `folder` beside the rule-based target's, `rule`, on the same starts."""
    eps = episodes(folder)
    assert [(e["seed"], e["map"]) for e in eps] == [(e["seed"], e["map"]) for e in rule], folder
    caught = [e["captured"] == "true" for e in eps]
    n = len(eps)
    low, high = wilson(sum(caught), n)
    time = sum(float(e["steps"]) for e in eps) / n
    diff = "–" if is_rule else paired_difference([e["captured"] == "true" for e in rule], caught)
    return f"| {team} | 1.0:{ratio} | {label} | {n} | {100 * sum(caught) / n:.1f} [{low:.1f}, {high:.1f}] | {time:.0f} | {diff} |"


def main(out: Path, sight_out: Path) -> None:
    print("| captors | v_p:v_e | target | episodes | SR % [95%] | Time | minus the rule-based target, points [95%] |")
    print("|---|---|---|---|---|---|---|")
    for team, ratio in [("mappo-sight", "1.0"), ("mappo-sight", "1.2"), ("expert7", "1.2")]:
        base = sight_out if team == "mappo-sight" else out
        rule = episodes(base / f"{team}-heuristic-{ratio}")
        for name in ["heuristic", "robust", "teacher", "rule", "teacher-no-prior", "rule-no-prior", "teacher-kl50",
                     "teacher-departures100", "teacher-departures100-sight"]:
            folder = (base if name in ("heuristic", "robust") else out) / f"{team}-{name}-{ratio}"
            if not (folder.exists() and any((x / "episodes.csv").exists() for x in folder.iterdir())):
                continue
            label = {
                "heuristic": "rule-based",
                "robust": "robust",
                "teacher": "distilled, prior 10",
                "rule": "control (KL to the rule), prior 10",
                "teacher-no-prior": "distilled, no prior",
                "rule-no-prior": "control (KL to the rule), no prior",
                "teacher-kl50": "distilled, prior 10, KL 50",
                "teacher-departures100": "distilled, prior 10, departures x100",
                "teacher-departures100-sight": "distilled, prior 10, departures x100, sight",
            }[name]
            print(table_row(team, ratio, label, folder, rule, name == "heuristic"))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
