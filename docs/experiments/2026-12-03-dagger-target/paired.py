"""Every target beside the rule-based target on the same starts: per team
and speed ratio, each target's capture rate (SR, 95% Wilson) and mean Time
(steps; an escape counts 500), and the mean paired difference of captures
(the target minus the rule-based target) with its 95% normal interval.
Prints a Markdown table. The helpers are the distillation page's.

    python paired.py OUT
OUT: what run.sh wrote.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "2026-12-02-distilled-target"))
from paired import episodes, table_row  # noqa: E402

LABELS = {
    "heuristic": "rule-based",
    "robust": "robust (the teacher)",
    "dagger-w1": "DAgger, prior 10",
    "dagger-w10": "DAgger, prior 10, departures x10",
    "dagger-w10-large-sight": "DAgger, prior 10, departures x10, larger network, sight",
    "dagger-w10-large-sight-more-data": "DAgger, as the larger one, 3x the aggregate, 2.08 M env steps",
    "dagger-w10-large-sight-one-model": "DAgger, as the larger one, teacher robust:10:heuristic",
}


def main(out: Path) -> None:
    print("| captors | v_p:v_e | target | episodes | SR % [95%] | Time | minus the rule-based target, points [95%] |")
    print("|---|---|---|---|---|---|---|")
    for team, ratio in [("mappo-sight", "1.0"), ("mappo-sight", "1.2"), ("expert7", "1.2"), ("greedy2", "1.2")]:
        done = lambda f: f.exists() and any((x / "episodes.csv").exists() for x in f.iterdir())  # noqa: E731
        if not done(out / f"{team}-heuristic-{ratio}"):
            continue
        rule = episodes(out / f"{team}-heuristic-{ratio}")
        for name, label in LABELS.items():
            folder = out / f"{team}-{name}-{ratio}"
            if not done(folder):
                continue
            print(table_row(team, ratio, label, folder, rule, name == "heuristic"))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
