"""The league's targets (league: the validation panel's choice; final: the
main learner as it stopped) against the rule-based target on the same starts:
per captor team and class, the SR (95% Wilson) and Time (mean steps) of
each, the learned target's departure rate, and the mean paired difference
of captures (learned minus rule-based; below zero: harder to catch) with
its 95% normal interval.

    python paired.py OUT   (the folders run.sh wrote: eval-TEAM-rule, eval-TEAM-league)
"""

import csv
import json
import math
import re
import sys
from pathlib import Path


def wilson(k: int, n: int) -> tuple[float, float]:
    z = 1.959964
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return 100 * (centre - half), 100 * (centre + half)


def settings(folder: Path) -> dict[str, tuple[list[dict], dict]]:
    """Map class -> (episodes, summary) of the eval folder."""
    out = {}
    for setting in sorted(folder.iterdir()):
        f = setting / "episodes.csv"
        if f.exists():
            m = re.search(r"_k\d+_r[0-9p]+_(.+)_[0-9a-f]{12}$", setting.name)
            assert m, f"{setting}: not an eval setting folder"
            out[m.group(1)] = (list(csv.DictReader(open(f))), json.load(open(setting / "summary.json")))
    return out


def main(out: Path) -> None:
    print("| captors | maps | episodes | rule-based SR % [95%] | Time | target | SR % [95%] | Time | departure % | paired difference, points [95%] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for team in ("greedy2", "mappo", "mappo-sight"):
        rule_dir = out / f"eval-{team}-rule"
        if not rule_dir.exists():
            continue
        rule = settings(rule_dir)
        for name in ("league", "final"):
            learned_dir = out / f"eval-{team}-{name}"
            if not learned_dir.exists():
                continue
            learned = settings(learned_dir)
            for maps, (a, _) in rule.items():
                if maps not in learned:
                    continue
                b, summary = learned[maps]
                assert [(e["seed"], e["map"]) for e in a] == [(e["seed"], e["map"]) for e in b], "not the same starts"
                n = len(a)
                ca = [e["captured"] == "true" for e in a]
                cb = [e["captured"] == "true" for e in b]
                d = [int(y) - int(x) for x, y in zip(ca, cb)]
                mean = sum(d) / n
                sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1)) if n > 1 else 0.0
                half = 1.959964 * sd / math.sqrt(n)
                time = lambda es: sum(int(e["steps"]) for e in es) / len(es)
                la, ha = wilson(sum(ca), n)
                lb, hb = wilson(sum(cb), n)
                dep = summary.get("target_departure")
                print(
                    f"| {team} | {maps} | {n} | {100 * sum(ca) / n:.1f} [{la:.1f}, {ha:.1f}] | {time(a):.0f} "
                    f"| {name} | {100 * sum(cb) / n:.1f} [{lb:.1f}, {hb:.1f}] | {time(b):.0f} "
                    f"| {'' if dep is None else f'{dep:.1f}'} "
                    f"| {100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}] |"
                )


if __name__ == "__main__":
    main(Path(sys.argv[1]))
