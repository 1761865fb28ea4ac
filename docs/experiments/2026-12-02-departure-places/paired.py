"""Paired comparison of targets on the same starts against one team: each
target's capture rate (SR, 95% Wilson) and mean Time (steps; failures
count 500) beside the base target's, the mean paired difference of
captures (target minus base) with its 95% normal interval, and the
target's departures (%) from the rule-based move.
A target played for fewer episodes is compared on the base's first
episodes, which have the same starts (an episode's start comes from the
evaluation seed and its index alone).
    python3 paired.py BASE OTHER...   (eval output folders)"""
import csv
import json
import math
import sys
from pathlib import Path


def wilson(k, n):
    z = 1.959964
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return 100 * (centre - half), 100 * (centre + half)


def setting(folder):
    (d,) = [d for d in Path(folder).iterdir() if (d / "setting.json").exists()]
    return list(csv.DictReader(open(d / "episodes.csv"))), json.load(open(d / "summary.json"))


base, others = sys.argv[1], sys.argv[2:]
base_episodes, _ = setting(base)
time = lambda es: sum(int(e["steps"]) for e in es) / len(es)
print("| captors | target | episodes | base SR % [95%] | Time | SR % [95%] | Time | paired difference, points [95%] | departures % |")
print("|---|---|---|---|---|---|---|---|---|")
for other in others:
    b, sb = setting(other)
    n = min(len(base_episodes), len(b))
    a, b = base_episodes[:n], b[:n]
    ca = [e["captured"] == "true" for e in a]
    la, ha = wilson(sum(ca), n)
    assert [e["seed"] for e in a] == [e["seed"] for e in b], f"{other}: not the same starts"
    assert [e["map"] for e in a] == [e["map"] for e in b], f"{other}: not the same maps"
    cb = [e["captured"] == "true" for e in b]
    d = [int(y) - int(x) for x, y in zip(ca, cb)]
    mean = sum(d) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1))
    half = 1.959964 * sd / math.sqrt(n)
    lb, hb = wilson(sum(cb), n)
    dep = sb.get("target_departure")
    print(
        f"| {sb['captors']} | {sb['target']} | {n} | {100 * sum(ca) / n:.1f} [{la:.1f}, {ha:.1f}] | {time(a):.0f} "
        f"| {100 * sum(cb) / n:.1f} [{lb:.1f}, {hb:.1f}] | {time(b):.0f} "
        f"| {100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}] | {'-' if dep is None else f'{dep:.2f}'} |"
    )
