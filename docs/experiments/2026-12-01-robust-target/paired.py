"""Paired comparison of the robust lookahead target with the rule-based
target on the same starts: per team and speed ratio, each target's capture
rate (SR, 95% Wilson) and mean Time (steps; failures count 500), the mean
paired difference of captures (robust minus rule-based) with its 95%
normal interval, and the share (%) of the robust target's decisions that
departed from the rule-based move. Prints a Markdown table.

    python paired.py OUT   (the folders run.sh or sight.sh wrote)
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


def main(out: Path) -> None:
    print("| captors | v_p:v_e | maps | episodes | rule-based SR % [95%] | Time | robust SR % [95%] | Time | paired difference, points [95%] | departures % |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for team in ["expert", "expert7", "mappo", "mappo-sight", "greedy2", "lomo"]:
        for ratio, maps in [("1.0", "large"), ("1.2", "small"), ("1.2", "medium"), ("1.2", "large")]:
            suffix = "" if maps == "large" else f"-{maps}"
            rule_dir, robust_dir = out / f"{team}-heuristic-{ratio}{suffix}", out / f"{team}-robust-{ratio}{suffix}"
            if not (rule_dir.exists() and robust_dir.exists()):
                continue
            try:
                (a, _), (b, summary) = setting(rule_dir), setting(robust_dir)
            except ValueError:
                continue
            assert [e["seed"] for e in a] == [e["seed"] for e in b], f"{team} {ratio}: not the same starts"
            assert [e["map"] for e in a] == [e["map"] for e in b], f"{team} {ratio}: not the same maps"
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
            dep = "–" if dep is None else f"{dep:.2f}"
            print(
                f"| {team} | 1.0:{ratio} | {maps} | {n} | {100 * sum(ca) / n:.1f} [{la:.1f}, {ha:.1f}] | {time(a):.0f} "
                f"| {100 * sum(cb) / n:.1f} [{lb:.1f}, {hb:.1f}] | {time(b):.0f} "
                f"| {100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}] | {dep} |"
            )


if __name__ == "__main__":
    main(Path(sys.argv[1]))
