"""Paired comparison of two targets on the same starts: for each eval
setting, the capture rate (SR, 95% Wilson) and mean Time of each, and the
mean paired difference of captures (second minus first) with its 95%
normal interval. Prints a Markdown table.

    python paired.py OUT   (the folders run.sh wrote)
"""

import csv
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


def episodes(folder: Path) -> dict[str, list[dict]]:
    """Setting folder name without its target part -> episodes."""
    out = {}
    for setting in sorted(folder.iterdir()):
        f = setting / "episodes.csv"
        if f.exists():
            m = re.search(r"_(k\d+_r[0-9p]+)_(.+)_[0-9a-f]{12}$", setting.name)
            assert m, f"{setting}: not an eval setting folder"
            out[(m.group(1), m.group(2))] = list(csv.DictReader(open(f)))
    return out


def main(out: Path) -> None:
    print("| captors | v_p:v_e | maps | episodes | rule-based SR % [95%] | Time | lookahead:10 SR % [95%] | Time | paired difference, points [95%] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for team in ["expert", "greedy2", "mappo"]:
        for ratio in ["1.0", "1.2"]:
            rule_dir, look_dir = out / f"{team}-heuristic-{ratio}", out / f"{team}-lookahead10-{ratio}"
            if not (rule_dir.exists() and look_dir.exists()):
                continue
            rule, look = episodes(rule_dir), episodes(look_dir)
            for key in rule:
                if key not in look:
                    continue
                a, b = rule[key], look[key]
                assert [e["seed"] for e in a] == [e["seed"] for e in b], f"{key}: not the same starts"
                n = len(a)
                ca = [e["captured"] == "true" for e in a]
                cb = [e["captured"] == "true" for e in b]
                d = [int(y) - int(x) for x, y in zip(ca, cb)]
                mean = sum(d) / n
                sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1)) if n > 1 else 0.0
                half = 1.959964 * sd / math.sqrt(n)
                time = lambda es: sum(int(e["steps"]) for e in es) / len(es)
                sra, srb = 100 * sum(ca) / n, 100 * sum(cb) / n
                la, ha = wilson(sum(ca), n)
                lb, hb = wilson(sum(cb), n)
                maps = key[1]
                print(
                    f"| {team} | 1.0:{ratio} | {maps} | {n} | {sra:.1f} [{la:.1f}, {ha:.1f}] | {time(a):.0f} "
                    f"| {srb:.1f} [{lb:.1f}, {hb:.1f}] | {time(b):.0f} "
                    f"| {100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}] |"
                )


if __name__ == "__main__":
    main(Path(sys.argv[1]))
