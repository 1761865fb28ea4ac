"""The robust-member league's players beside players of the same budget
on the same starts. First its captors against cooperative MAPPO (team R)
on each target: each team's capture rate (SR, 95% Wilson), mean Time
(steps; an escape counts 500) and the mean paired difference of captures
(the league's captors minus team R) with its 95% normal interval. Then
its exported target against the rule-based target for each test team:
SR, Time and the paired difference (the exported target minus the
rule-based one). Prints two Markdown tables. The helpers are the
distillation page's.

    python paired.py OUT
OUT: what run.sh wrote.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "2026-12-02-distilled-target"))
from paired import episodes, paired_difference, wilson  # noqa: E402


def caught(eps: list[dict]) -> list[bool]:
    return [e["captured"] == "true" for e in eps]


def cell(eps: list[dict]) -> str:
    c = caught(eps)
    low, high = wilson(sum(c), len(c))
    time = sum(float(e["steps"]) for e in eps) / len(eps)
    return f"{100 * sum(c) / len(c):.1f} [{low:.1f}, {high:.1f}] | {time:.0f}"


def same_starts(a: list[dict], b: list[dict]) -> None:
    assert [(e["seed"], e["map"]) for e in a] == [(e["seed"], e["map"]) for e in b]


def main(out: Path) -> None:
    print("| v_p:v_e | target | episodes | league's captors: SR % [95%] | Time | team R: SR % [95%] | Time | league minus team R, points [95%] |")
    print("|---|---|---|---|---|---|---|---|")
    for ratio in ["1.2", "1.0"]:
        for name, label in [("rule", "rule-based"), ("robust", "robust (a league member)")]:
            league, team_r = episodes(out / f"captors-vs-{name}-{ratio}"), episodes(out / f"rule-vs-{name}-{ratio}")
            same_starts(league, team_r)
            diff = paired_difference(caught(team_r), caught(league))
            print(f"| 1.0:{ratio} | {label} | {len(league)} | {cell(league)} | {cell(team_r)} | {diff} |")
    print()
    print("| captors | v_p:v_e | episodes | rule-based target: SR % [95%] | Time | exported target: SR % [95%] | Time | exported minus rule-based, points [95%] |")
    print("|---|---|---|---|---|---|---|---|")
    for team, label in [("rule", "team R (cooperative MAPPO)"), ("greedy2", "`greedy:2`")]:
        if not (out / f"{team}-vs-target-1.2").exists():
            continue
        rule, target = episodes(out / f"{team}-vs-rule-1.2"), episodes(out / f"{team}-vs-target-1.2")
        same_starts(rule, target)
        diff = paired_difference(caught(rule), caught(target))
        print(f"| {label} | 1.0:1.2 | {len(rule)} | {cell(rule)} | {cell(target)} | {diff} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
